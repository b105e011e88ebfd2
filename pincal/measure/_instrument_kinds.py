"""The built-in scalar instruments: ballbar, sphere probe, reference planes, dial gauge.

Each reads one scalar per pose of the tool point ``p`` (world frame [m]) and has its
own unknown parameters θ, identified jointly with the machine's:

* :class:`Distance` (``distance``) — double ballbar between the tool point and a fixed
  pivot ``c``: ``v = ‖p − c‖ + e``; θ = (pivot_x, pivot_y, pivot_z, length_offset e) [m].
* :class:`Sphere` (``sphere``) — touch probe on a reference sphere of calibrated radius r
  (probe-tip radius included): ``v = ‖p − c‖ − r`` (the probe's deflection, 0 for a
  touch trigger); θ = (centre_x, centre_y, centre_z) [m].
* :class:`Plane` (``plane``) — contacts on reference planes j = 0..P−1 (a plane id per
  row): ``v = n_j · p − d_j`` with ``n_j = (n0_j + a_j t1_j + b_j t2_j)/‖·‖`` about a
  reference normal n0_j (t1, t2 orthonormal to it); θ = (a_j [rad], b_j [rad], d_j [m])
  per plane.
* :class:`Point` (``point``) — one dial-gauge / Z-probe axis along a fixed unit
  direction u: ``v = u · p − o``; θ = (offset o) [m].

What each trusts (:meth:`Instrument.declared_constants`): the ballbar its length scale
(a bar-length or transducer-gain error k adds ``k v``), the sphere probe its declared
radius (an error δr adds ``−δr``), planes and dial gauge their gain (``k v``). A
plane's tilt is fitted, not trusted; the dial gauge's declared axis direction is not
offered (an angle about a zero value has no relative bound to judge it against).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from pincal.errors import MeasurementError
from pincal.measure._instrument_kind import (
    DeclaredConstant,
    HeaderValues,
    Instrument,
    unit_vector,
)

__all__ = ["Distance", "Plane", "Point", "Sphere"]

#: typical set-ups: pivot / sphere centre this far below the centre of the tool points [m]
_BELOW = np.array([0.0, 0.0, 0.1])


def _gain(inst: Instrument, P: np.ndarray, theta: np.ndarray, ids: np.ndarray | None,
          name: str, error: str) -> tuple[DeclaredConstant, ...]:  # fmt: skip
    """A relative scale k of the readings (``∂v/∂k = v``), trusted from the instrument."""
    v = inst.predict(P, theta, ids)[0]
    rests = "the scale rests on the instrument's own calibration"
    return (DeclaredConstant(name, 1.0, "1", v, error, rests),)


def _radial(P: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    d = P - c
    r = np.linalg.norm(d, axis=1)
    if np.any(r < 1e-12):
        raise MeasurementError("a tool position coincides with the pivot / sphere centre")
    return r, d / r[:, None]


def _coplanar(P: np.ndarray) -> np.ndarray | None:
    """The unit normal (z component ≥ 0) of tool points that lie in one plane, else None."""
    if len(P) < 3:
        return None
    _, s, vt = np.linalg.svd(P - P.mean(axis=0), full_matrices=True)
    if s[0] <= 0 or s[-1] > 1e-9 * s[0]:
        return None
    n = vt[-1]
    return n if n[2] >= 0 else -n


def _centre_in_plane(P: np.ndarray, L: np.ndarray, n: np.ndarray) -> np.ndarray:
    """Centre c (3,) [m] of a sphere through coplanar points P at distances L, below them.

    In the plane of the points ``L² = |p − c'|² + h²`` (c' the centre's foot point, h its
    height) is linear in (c', |c'|² + h²); which side of the plane the centre lies on no
    reading tells: it is put on the side of −n (below a horizontal plane).
    """
    t1 = np.cross(n, np.eye(3)[int(np.argmin(np.abs(n)))])
    t1 /= np.linalg.norm(t1)
    T = np.column_stack([t1, np.cross(n, t1)])
    origin = P.mean(axis=0)
    Q = (P - origin) @ T
    A = np.column_stack([2 * Q, -np.ones(len(P))])
    a, b, k = np.linalg.lstsq(A, np.sum(Q**2, axis=1) - L**2, rcond=None)[0]
    h = float(np.sqrt(max(k - a * a - b * b, 0.0)))
    return origin + T @ np.array([a, b]) - h * n


@dataclass(frozen=True)
class Distance(Instrument):
    """Double ballbar from a fixed pivot to the tool point (pivot and bar offset unknown)."""

    kind: ClassVar[str] = "distance"
    description: ClassVar[str] = "double ballbar: distance from a fixed pivot"
    std: float = 1e-6

    def __post_init__(self) -> None:
        self._check_std()

    @property
    def parameter_names(self) -> tuple[str, ...]:
        return ("pivot_x", "pivot_y", "pivot_z", "length_offset")

    def _predict(
        self, P: np.ndarray, theta: np.ndarray, ids: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        r, u = _radial(P, theta[:3])
        dth = np.column_stack([-u, np.ones(len(P))])
        return r + theta[3], u, dth

    def start(
        self, P: np.ndarray, v: np.ndarray, ids: np.ndarray | None
    ) -> tuple[Instrument, np.ndarray]:
        n = _coplanar(P)
        if n is not None:  # a planar machine: the bar offset starts at 0
            return self, np.r_[_centre_in_plane(P, v, n), 0.0]
        # |p|² − v² = 2 p·c − 2 v e + (e² − |c|²), linear in (c, e, e² − |c|²)
        A = np.column_stack([2 * P, -2 * v, np.ones(len(P))])
        sol = np.linalg.lstsq(A, np.sum(P**2, axis=1) - v**2, rcond=None)[0]
        return self, sol[:4]

    @classmethod
    def typical(
        cls, P: np.ndarray, std: float | None = None
    ) -> tuple[Instrument, np.ndarray, np.ndarray | None]:
        c = np.asarray(P, dtype=float).mean(axis=0) - _BELOW
        return cls(cls.default_std if std is None else std), np.r_[c, 0.0], None

    def candidate_sphere(
        self, theta: np.ndarray, home: np.ndarray
    ) -> tuple[np.ndarray, float] | None:
        c = np.asarray(theta[:3], dtype=float)
        return c, float(np.linalg.norm(np.asarray(home) - c))

    def declared_constants(
        self, P: np.ndarray, theta: np.ndarray, ids: np.ndarray | None = None
    ) -> tuple[DeclaredConstant, ...]:
        return _gain(self, P, theta, ids, "the length scale",
                     "a scale error of the readings (a bar length, a gain)")  # fmt: skip


@dataclass(frozen=True)
class Sphere(Instrument):
    """Touch probe on a reference sphere of calibrated radius (centre unknown)."""

    kind: ClassVar[str] = "sphere"
    description: ClassVar[str] = "touch probe on a reference sphere of calibrated radius"
    std: float = 1e-6
    radius: float = 0.02

    def __post_init__(self) -> None:
        self._check_std()
        if not (np.isfinite(self.radius) and self.radius > 0):
            raise MeasurementError(f"a sphere needs a calibrated radius > 0 [m], got {self.radius}")

    @property
    def parameter_names(self) -> tuple[str, ...]:
        return ("centre_x", "centre_y", "centre_z")

    def _predict(
        self, P: np.ndarray, theta: np.ndarray, ids: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        r, u = _radial(P, theta[:3])
        return r - self.radius, u, -u

    def start(
        self, P: np.ndarray, v: np.ndarray, ids: np.ndarray | None
    ) -> tuple[Instrument, np.ndarray]:
        n = _coplanar(P)
        if n is not None:
            return self, _centre_in_plane(P, self.radius + v, n)
        A = np.column_stack([2 * P, -np.ones(len(P))])  # 2 p·c − |c|² = |p|² − (r + v)²
        sol = np.linalg.lstsq(A, np.sum(P**2, axis=1) - (self.radius + v) ** 2, rcond=None)[0]
        return self, sol[:3]

    @classmethod
    def from_header(cls, std: float, header: HeaderValues) -> Sphere:
        return cls(std, header.length("radius"))

    def header(self, length: Callable[[float], str], number: Callable[[float], str]) -> list[str]:
        return [f"radius: {length(self.radius)}"]

    @classmethod
    def typical(
        cls, P: np.ndarray, std: float | None = None
    ) -> tuple[Instrument, np.ndarray, np.ndarray | None]:
        c = np.asarray(P, dtype=float).mean(axis=0) - _BELOW
        return cls(cls.default_std if std is None else std, radius=0.02), c, None

    def candidate_sphere(
        self, theta: np.ndarray, home: np.ndarray
    ) -> tuple[np.ndarray, float] | None:
        return np.asarray(theta[:3], dtype=float), float(self.radius)

    def declared_constants(
        self, P: np.ndarray, theta: np.ndarray, ids: np.ndarray | None = None
    ) -> tuple[DeclaredConstant, ...]:
        ones = np.ones(len(np.atleast_2d(P)))
        rests = "the radius rests on its declared value"
        return (DeclaredConstant("the sphere radius", float(self.radius), "m", -ones,
                                 "a radius error", rests),)  # fmt: skip


@dataclass(frozen=True)
class Point(Instrument):
    """Dial gauge / Z-probe along a fixed axis (its offset unknown)."""

    kind: ClassVar[str] = "point"
    description: ClassVar[str] = "dial gauge along a fixed axis"
    std: float = 1e-6
    direction: tuple[float, float, float] = (0.0, 0.0, 1.0)

    def __post_init__(self) -> None:
        self._check_std()
        object.__setattr__(self, "direction", unit_vector(self.direction, "direction"))

    @property
    def parameter_names(self) -> tuple[str, ...]:
        return ("offset",)

    def _predict(
        self, P: np.ndarray, theta: np.ndarray, ids: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        u = np.asarray(self.direction)
        return P @ u - theta[0], np.tile(u, (len(P), 1)), -np.ones((len(P), 1))

    def start(
        self, P: np.ndarray, v: np.ndarray, ids: np.ndarray | None
    ) -> tuple[Instrument, np.ndarray]:
        return self, np.array([float(np.mean(P @ np.asarray(self.direction) - v))])

    @classmethod
    def from_header(cls, std: float, header: HeaderValues) -> Point:
        return cls(std, tuple(header.vector("direction", 3, "0 0 1")))  # type: ignore[arg-type]

    def header(self, length: Callable[[float], str], number: Callable[[float], str]) -> list[str]:
        return ["direction: " + ", ".join(number(x) for x in self.direction)]

    @classmethod
    def typical(
        cls, P: np.ndarray, std: float | None = None
    ) -> tuple[Instrument, np.ndarray, np.ndarray | None]:
        return cls(cls.default_std if std is None else std), np.zeros(1), None

    def declared_constants(
        self, P: np.ndarray, theta: np.ndarray, ids: np.ndarray | None = None
    ) -> tuple[DeclaredConstant, ...]:
        return _gain(self, P, theta, ids, "the gauge's gain", "a gain error of the readings")


def _tangents(n0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors orthonormal to the unit vector ``n0`` (a fixed, smooth choice)."""
    a = np.eye(3)[int(np.argmin(np.abs(n0)))]
    t1 = np.cross(n0, a)
    t1 /= np.linalg.norm(t1)
    return t1, np.cross(n0, t1)


@dataclass(frozen=True)
class Plane(Instrument):
    """Contacts on reference planes, a plane id per row (each plane unknown).

    ``normals`` are the reference unit normals n0_j, one per plane id; they may be empty
    until :meth:`start` fits them to the nominal contact points.
    """

    kind: ClassVar[str] = "plane"
    description: ClassVar[str] = "contacts on reference planes (a plane id per row)"
    id_column: ClassVar[str | None] = "plane"
    std: float = 1e-6
    normals: tuple[tuple[float, float, float], ...] = ()

    def __post_init__(self) -> None:
        self._check_std()
        object.__setattr__(self, "normals", tuple(
            unit_vector(n, f"plane normal {j}") for j, n in enumerate(self.normals)))  # fmt: skip

    @property
    def n_planes(self) -> int:
        """Number of planes touched."""
        return len(self.normals)

    @property
    def n_ids(self) -> int:
        return self.n_planes

    @property
    def parameter_names(self) -> tuple[str, ...]:
        return tuple(f"plane{j}_{s}" for j in range(self.n_planes) for s in ("a", "b", "d"))

    @property
    def parameter_units(self) -> tuple[str, ...]:
        return ("rad", "rad", "m") * self.n_planes

    def _predict(
        self, P: np.ndarray, theta: np.ndarray, ids: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        assert ids is not None
        if ids.size and ids.max() >= self.n_planes:
            raise MeasurementError(
                f"plane ids must be (m,) integers in [0, {self.n_planes}), one per row"
            )
        m = len(P)
        v, dp, dth = np.empty(m), np.empty((m, 3)), np.zeros((m, theta.size))
        for j in range(self.n_planes):
            rows = ids == j
            if not np.any(rows):
                continue
            a, b, dj = theta[3 * j : 3 * j + 3]
            n0 = np.asarray(self.normals[j])
            t1, t2 = _tangents(n0)
            w = n0 + a * t1 + b * t2
            s = float(np.linalg.norm(w))
            n = w / s
            Pj = P[rows]
            v[rows] = Pj @ n - dj
            dp[rows] = n
            proj = (np.eye(3) - np.outer(n, n)) / s  # d n / d w
            dth[rows, 3 * j] = Pj @ (proj @ t1)
            dth[rows, 3 * j + 1] = Pj @ (proj @ t2)
            dth[rows, 3 * j + 2] = -1.0
        return v, dp, dth

    def start(
        self, P: np.ndarray, v: np.ndarray, ids: np.ndarray | None
    ) -> tuple[Instrument, np.ndarray]:
        assert ids is not None
        inst = self
        if self.n_planes == 0:
            normals = []
            for j in range(int(ids.max()) + 1 if ids.size else 0):
                Pj = P[ids == j]
                if len(Pj) < 3:
                    raise MeasurementError(f"plane {j} has {len(Pj)} contacts; give at least 3")
                n = np.linalg.svd(Pj - Pj.mean(axis=0))[2][-1]
                normals.append(n if n[np.argmax(np.abs(n))] > 0 else -n)
            inst = Plane(self.std, tuple(tuple(n) for n in normals))  # type: ignore[misc]
        theta = np.zeros(len(inst.parameter_names))
        for j in range(inst.n_planes):
            rows = ids == j
            if np.any(rows):
                theta[3 * j + 2] = float(np.mean(P[rows] @ np.asarray(inst.normals[j]) - v[rows]))
        return inst, theta

    @classmethod
    def from_header(cls, std: float, header: HeaderValues) -> Plane:
        if not header.has("normal"):
            return cls(std)
        rows = sorted(header.vectors("normal", 4), key=lambda r: r[0])
        if [int(r[0]) for r in rows] != list(range(len(rows))):
            raise MeasurementError("normal ids must be 0, 1, … without gaps")
        return cls(std, tuple(tuple(r[1:]) for r in rows))  # type: ignore[misc]

    def header(self, length: Callable[[float], str], number: Callable[[float], str]) -> list[str]:
        return [f"normal: {j}, " + ", ".join(number(x) for x in n)
                for j, n in enumerate(self.normals)]  # fmt: skip

    @classmethod
    def typical(
        cls, P: np.ndarray, std: float | None = None
    ) -> tuple[Instrument, np.ndarray, np.ndarray | None]:
        P = np.asarray(P, dtype=float)
        inst = cls(cls.default_std if std is None else std,
                   normals=((0.0, 0.0, 1.0), (1.0, 0.0, 0.0)))  # fmt: skip
        theta = np.array([0.0, 0.0, P[:, 2].min(), 0.0, 0.0, P[:, 0].min()])
        return inst, theta, np.arange(len(P)) % 2

    def declared_constants(
        self, P: np.ndarray, theta: np.ndarray, ids: np.ndarray | None = None
    ) -> tuple[DeclaredConstant, ...]:
        return _gain(self, P, theta, ids, "the probe's gain", "a gain error of the readings")
