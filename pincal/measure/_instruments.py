"""Instruments that see less than a full pose: ballbar, touch probe, planes, dial gauge.

Each instrument reads one scalar per pose of the tool point ``p`` (the measured frame's
origin, world frame [m]) and has its own unknown parameters θ, identified jointly with
the machine's:

* ``distance`` — double ballbar between the tool point and a fixed pivot ``c``:
  ``v = ‖p − c‖ + e``; θ = (pivot_x, pivot_y, pivot_z, length_offset e) [m].
* ``sphere`` — touch probe on a reference sphere of calibrated radius r (probe-tip
  radius included): ``v = ‖p − c‖ − r`` (the probe's deflection, 0 for a touch
  trigger); θ = (centre_x, centre_y, centre_z) [m].
* ``plane`` — contacts on reference planes j = 0..P−1 (a plane id per row):
  ``v = n_j · p − d_j`` with ``n_j = (n0_j + a_j t1_j + b_j t2_j)/‖·‖`` about a reference
  normal n0_j (t1, t2 orthonormal to it); θ = (a_j [rad], b_j [rad], d_j [m]) per plane.
* ``point`` — one dial-gauge / Z-probe axis along a fixed unit direction u:
  ``v = u · p − o``; θ = (offset o) [m].

:meth:`Instrument.predict` returns the readings with their exact derivatives with
respect to ``p`` and θ; the machine part of the identification Jacobian is
``∂v/∂p · ∂p/∂x`` with ``∂p/∂x`` from :func:`pincal.sensitivity.pose_sensitivity`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from pincal.errors import MeasurementError
from pincal.model import Mechanism

__all__ = [
    "INSTRUMENT_KINDS",
    "Instrument",
    "InstrumentData",
    "initial_instrument_values",
    "simulate_instrument",
]

#: the scalar instrument kinds
INSTRUMENT_KINDS = ("distance", "sphere", "plane", "point")


def _tangents(n0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors orthonormal to the unit vector ``n0`` (a fixed, smooth choice)."""
    a = np.eye(3)[int(np.argmin(np.abs(n0)))]
    t1 = np.cross(n0, a)
    t1 /= np.linalg.norm(t1)
    return t1, np.cross(n0, t1)


def _unit(v: object, what: str) -> tuple[float, float, float]:
    arr = np.asarray(v, dtype=float).reshape(-1)
    norm = float(np.linalg.norm(arr)) if arr.size == 3 else 0.0
    if arr.size != 3 or not np.all(np.isfinite(arr)) or norm < 1e-12:
        raise MeasurementError(f"{what} must be a non-zero 3-vector, got {v!r}")
    return tuple(float(x) for x in arr / norm)  # type: ignore[return-value]


@dataclass(frozen=True)
class Instrument:
    """A scalar instrument: its kind, noise and fixed geometry.

    Attributes:
        kind: one of :data:`INSTRUMENT_KINDS`.
        std: 1σ noise of one reading [m] (> 0).
        radius: calibrated sphere radius [m] (``sphere``; > 0).
        direction: unit direction of the gauge axis (``point``; default +z).
        normals: reference unit normals n0_j, one per plane id (``plane``; may be empty
            until :func:`initial_instrument_values` fits them from nominal positions).

    Raises:
        MeasurementError: unknown kind, std ≤ 0, radius ≤ 0 for a sphere, bad vectors.
    """

    kind: str
    std: float = 1e-6
    radius: float = 0.0
    direction: tuple[float, float, float] = (0.0, 0.0, 1.0)
    normals: tuple[tuple[float, float, float], ...] = ()

    def __post_init__(self) -> None:
        if self.kind not in INSTRUMENT_KINDS:
            raise MeasurementError(
                f"unknown instrument kind {self.kind!r}; choose from {INSTRUMENT_KINDS} "
                "(or use a pose/position measurement file)"
            )
        if not (np.isfinite(self.std) and self.std > 0):
            raise MeasurementError(f"instrument std must be finite and > 0 [m], got {self.std}")
        if self.kind == "sphere" and not (np.isfinite(self.radius) and self.radius > 0):
            raise MeasurementError(f"a sphere needs a calibrated radius > 0 [m], got {self.radius}")
        object.__setattr__(self, "direction", _unit(self.direction, "direction"))
        object.__setattr__(
            self,
            "normals",
            tuple(_unit(n, f"plane normal {j}") for j, n in enumerate(self.normals)),
        )

    @property
    def n_planes(self) -> int:
        return len(self.normals)

    @property
    def parameter_names(self) -> tuple[str, ...]:
        """Names of θ, in order."""
        if self.kind == "distance":
            return ("pivot_x", "pivot_y", "pivot_z", "length_offset")
        if self.kind == "sphere":
            return ("centre_x", "centre_y", "centre_z")
        if self.kind == "point":
            return ("offset",)
        return tuple(f"plane{j}_{s}" for j in range(self.n_planes) for s in ("a", "b", "d"))

    @property
    def parameter_units(self) -> tuple[str, ...]:
        """``"m"`` / ``"rad"`` per θ entry."""
        return tuple("rad" if n[-2:] in ("_a", "_b") else "m" for n in self.parameter_names)

    def _check(self, P: np.ndarray, theta: np.ndarray, plane: np.ndarray | None):
        P = np.atleast_2d(np.asarray(P, dtype=float))
        theta = np.asarray(theta, dtype=float).reshape(-1)
        if P.ndim != 2 or P.shape[1] != 3:
            raise MeasurementError(f"tool positions must be (m, 3), got {P.shape}")
        if theta.size != len(self.parameter_names):
            raise MeasurementError(
                f"{self.kind} instrument has {len(self.parameter_names)} parameters "
                f"{self.parameter_names}, got {theta.size} values"
            )
        ids = None
        if self.kind == "plane":
            ids = np.zeros(len(P), dtype=int) if plane is None else np.asarray(plane, dtype=int)
            if ids.shape != (len(P),) or (
                ids.size and (ids.min() < 0 or ids.max() >= self.n_planes)
            ):
                raise MeasurementError(
                    f"plane ids must be (m,) integers in [0, {self.n_planes}), one per row"
                )
        return P, theta, ids

    def predict(
        self, P: np.ndarray, theta: np.ndarray, plane: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Readings at tool positions and their exact derivatives.

        Args:
            P: (m, 3) tool positions [m] (world frame).
            theta: (k,) instrument parameters (see :attr:`parameter_names`).
            plane: (m,) plane ids (``plane`` kind only).

        Returns:
            v (m,) readings [m], dv/dp (m, 3), dv/dθ (m, k).

        Raises:
            MeasurementError: wrong shapes, plane ids out of range.
        """
        P, theta, ids = self._check(P, theta, plane)
        m, k = len(P), theta.size
        dth = np.zeros((m, k))
        if self.kind in ("distance", "sphere"):
            d = P - theta[:3]
            r = np.linalg.norm(d, axis=1)
            if np.any(r < 1e-12):
                raise MeasurementError("a tool position coincides with the pivot / sphere centre")
            u = d / r[:, None]
            dth[:, :3] = -u
            if self.kind == "distance":
                dth[:, 3] = 1.0
                return r + theta[3], u, dth
            return r - self.radius, u, dth
        if self.kind == "point":
            u = np.asarray(self.direction)
            dth[:, 0] = -1.0
            return P @ u - theta[0], np.tile(u, (m, 1)), dth
        v = np.empty(m)
        dp = np.empty((m, 3))
        assert ids is not None
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
            # d n / d w = (I − n nᵀ) / s
            proj = (np.eye(3) - np.outer(n, n)) / s
            dth[rows, 3 * j] = Pj @ (proj @ t1)
            dth[rows, 3 * j + 1] = Pj @ (proj @ t2)
            dth[rows, 3 * j + 2] = -1.0
        return v, dp, dth


@dataclass(frozen=True, eq=False)
class InstrumentData:
    """Scalar readings of one instrument at m poses.

    Attributes:
        instrument: the instrument (kind, noise, geometry).
        q_act: (m, n_act) commanded actuator values [m, rad].
        values: (m,) readings [m].
        actuated: actuated joint names (columns of ``q_act``).
        frame: the measured frame whose origin is the tool point.
        plane: (m,) plane ids (``plane`` kind), else None.
        initial: (k,) start values of θ, or None (estimated from the nominal model).

    Raises:
        MeasurementError: inconsistent shapes or non-finite values.
    """

    instrument: Instrument
    q_act: np.ndarray
    values: np.ndarray
    actuated: tuple[str, ...]
    frame: str
    plane: np.ndarray | None = None
    initial: np.ndarray | None = field(default=None)

    def __post_init__(self) -> None:
        q = np.atleast_2d(np.asarray(self.q_act, dtype=float))
        v = np.asarray(self.values, dtype=float).reshape(-1)
        if q.shape != (v.size, len(self.actuated)):
            raise MeasurementError(
                f"q_act must be ({v.size}, {len(self.actuated)}) for {v.size} readings, "
                f"got {q.shape}"
            )
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
            raise MeasurementError("instrument data contain NaN or inf")
        object.__setattr__(self, "q_act", q)
        object.__setattr__(self, "values", v)
        object.__setattr__(self, "actuated", tuple(self.actuated))
        if self.instrument.kind == "plane":
            ids = np.zeros(v.size, dtype=int) if self.plane is None else np.asarray(self.plane)
            if ids.shape != (v.size,) or not np.all(ids == np.round(ids)) or np.any(ids < 0):
                raise MeasurementError("plane ids must be one integer ≥ 0 per reading")
            object.__setattr__(self, "plane", ids.astype(int))
        elif self.plane is not None:
            raise MeasurementError(
                f"plane ids belong to the plane kind, not {self.instrument.kind!r}"
            )
        if self.initial is not None:
            x0 = np.asarray(self.initial, dtype=float).reshape(-1)
            object.__setattr__(self, "initial", x0)

    def __len__(self) -> int:
        return self.values.size

    @property
    def kind(self) -> str:
        return self.instrument.kind


def initial_instrument_values(
    data: InstrumentData, positions: np.ndarray
) -> tuple[Instrument, np.ndarray]:
    """The instrument with its reference geometry and start values θ0 from tool positions.

    Fits the instrument to the tool positions of the nominal model (linear least
    squares for sphere and ballbar, an SVD plane fit per plane id), unless
    ``data.initial`` gives θ0.

    Args:
        data: the readings.
        positions: (m, 3) nominal tool positions [m].

    Returns:
        (instrument with plane normals filled in, θ0 (k,)).

    Raises:
        MeasurementError: ``data.initial`` of the wrong length.
    """
    inst, v, P = data.instrument, data.values, np.asarray(positions, dtype=float)
    if inst.kind == "plane" and inst.n_planes == 0:
        assert data.plane is not None
        normals = []
        for j in range(int(data.plane.max()) + 1):
            Pj = P[data.plane == j]
            if len(Pj) < 3:
                raise MeasurementError(f"plane {j} has {len(Pj)} contacts; give at least 3")
            n = np.linalg.svd(Pj - Pj.mean(axis=0))[2][-1]
            normals.append(n if n[np.argmax(np.abs(n))] > 0 else -n)
        inst = Instrument("plane", inst.std, normals=tuple(tuple(n) for n in normals))
    k = len(inst.parameter_names)
    if data.initial is not None:
        if data.initial.size != k:
            raise MeasurementError(f"initial has {data.initial.size} values, {inst.kind} needs {k}")
        return inst, data.initial.copy()
    if inst.kind == "distance":  # |p|² − v² = 2 p·c − 2 v e + (e² − |c|²)
        A = np.column_stack([2 * P, -2 * v, np.ones(len(P))])
        sol = np.linalg.lstsq(A, np.sum(P**2, axis=1) - v**2, rcond=None)[0]
        return inst, sol[:4]
    if inst.kind == "sphere":  # 2 p·c − |c|² = |p|² − (r + v)²
        A = np.column_stack([2 * P, -np.ones(len(P))])
        sol = np.linalg.lstsq(A, np.sum(P**2, axis=1) - (inst.radius + v) ** 2, rcond=None)[0]
        return inst, sol[:3]
    if inst.kind == "point":
        return inst, np.array([float(np.mean(P @ np.asarray(inst.direction) - v))])
    theta = np.zeros(k)
    assert data.plane is not None
    for j in range(inst.n_planes):
        rows = data.plane == j
        if np.any(rows):
            theta[3 * j + 2] = float(np.mean(P[rows] @ np.asarray(inst.normals[j]) - v[rows]))
    return inst, theta


def simulate_instrument(
    actual: Mechanism,
    instrument: Instrument,
    theta: np.ndarray,
    q_act_rows: np.ndarray,
    rng: np.random.Generator | None = None,
    plane: np.ndarray | None = None,
    noise: bool = True,
) -> InstrumentData:
    """Readings of ``instrument`` (true parameters θ) on the ``actual`` machine.

    Args:
        actual: the machine measured (simulation truth).
        instrument: the instrument.
        theta: (k,) its true parameter values [m, rad] (see
            :attr:`Instrument.parameter_names`).
        q_act_rows: (m, n_act) actuator values [m, rad].
        rng: generator for the noise (default: a fresh one).
        plane: (m,) plane ids (``plane`` kind).
        noise: add N(0, std²) to each reading.

    Returns:
        InstrumentData (``initial`` None).

    Raises:
        MeasurementError: bad θ or plane ids; ConvergenceError: a row cannot be assembled.
    """
    rows = np.atleast_2d(np.asarray(q_act_rows, dtype=float))
    P = np.array([actual.frame_placement(q).translation for q in actual.configurations(rows)])
    v = instrument.predict(P, theta, plane)[0]
    if noise:
        rng = rng if rng is not None else np.random.default_rng()
        v = v + rng.normal(0.0, instrument.std, v.shape)
    return InstrumentData(instrument, rows.copy(), v, actual.actuated, actual.measured_frame, plane)
