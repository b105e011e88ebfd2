"""Artefact instrument: a face of the measured frame pressed flush against a plane.

A humanoid calibrated by touching a table: at each pose a flat face of the robot (a
palm, a gripper's side, a sole) lies flush on a plane whose placement is unknown. No
instrument reads anything; the pose itself is the measurement. A flush touch fixes
three things of the measured frame (p [m], R):

* its **height** above the plane, ``n·p − d = 0`` (the frame's origin is on the face);
* its **two tilts**: the face's normal ``a`` (a unit axis of the frame, e.g. +z of a
  palm frame) is the plane's normal, ``R·a = n``.

Residuals per pose (``reference − model``, reference 0)::

    r_h = d − n·p,   r_k = e_k·(n − R·a)   (k = 1, 2)

with ``e_1, e_2`` a fixed orthonormal basis across the declared approximate normal
``n0``; to first order ``r_k`` are the two tilts [rad] of the face. The plane is
``n(φ1, φ2) = (n0 + φ1 e_1 + φ2 e_2) / ‖·‖`` and its offset ``d`` [m] (``n·x = d`` on
the plane): three unknowns shared by every dataset of the same plane name
(:attr:`FlushContact.plane`), started from the nominal poses.

Not fitted here, by design: where the contact point lies *within* the face (no flush
touch sees it), and the face's offset along its normal, which is the plane offset ``d``
exactly (``n·(p + h a) = n·p + h``). A tool frame's position along ``a`` in the
machine's preset is reported as absorbed by ``d``.

:class:`FlushContact` is the ``flush`` kind of :class:`pincal.measure.Artefact`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from pincal.errors import MeasurementError
from pincal.measure._artefact_kind import Artefact, SharedTerms

__all__ = ["FlushContact", "flush_residuals", "plane_basis"]


def _unit(v: object, what: str) -> np.ndarray:
    u = np.asarray(v, dtype=float).reshape(-1)
    norm = float(np.linalg.norm(u)) if u.size == 3 and np.all(np.isfinite(u)) else 0.0
    if norm < 1e-9:
        raise MeasurementError(f"{what} must be 3 finite numbers, not all 0, got {v!r}")
    return u / norm


def plane_basis(n0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A fixed orthonormal pair (e_1, e_2) across the unit vector ``n0``."""
    helper = np.eye(3)[int(np.argmin(np.abs(n0)))]
    e1 = np.cross(n0, helper)
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(n0, e1)


def _normal(n0: np.ndarray, phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The plane normal n (3,) at (φ1, φ2) and ∂n/∂φ (3, 2)."""
    e1, e2 = plane_basis(n0)
    u = n0 + phi[0] * e1 + phi[1] * e2
    s = float(np.linalg.norm(u))
    n = u / s
    E = np.column_stack([e1, e2])
    return n, (E - np.outer(n, n @ E)) / s


def flush_residuals(
    P: np.ndarray, Rs: np.ndarray, axis: np.ndarray, n0: np.ndarray, phi: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Residuals (m, 3) ``[r_h, r_1, r_2]`` and ∂/∂p (m, 3, 3), ∂/∂ω (m, 3, 3), ∂/∂φ (m, 3, 3).

    Args:
        P: (m, 3) positions of the measured frame [m].
        Rs: (m, 3, 3) its orientations.
        axis: (3,) the face's unit normal in the frame.
        n0: (3,) the plane's declared approximate unit normal.
        phi: (φ1, φ2, d) the plane's unknowns [-, -, m].
    """
    n, dn = _normal(n0, phi[:2])
    e1, e2 = plane_basis(n0)
    E = np.vstack([e1, e2])  # (2, 3)
    m = len(P)
    Ra = Rs @ axis  # (m, 3)
    r = np.empty((m, 3))
    r[:, 0] = phi[2] - P @ n
    r[:, 1:] = (n - Ra) @ E.T
    dp = np.zeros((m, 3, 3))
    dp[:, 0, :] = -n
    # R·exp(ω)·a ≈ R·a + R·(ω × a) = R·a − R·[a]×·ω
    ax = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    dw = np.zeros((m, 3, 3))
    dw[:, 1:, :] = np.einsum("kj,mjl,li->mki", E, Rs, ax)
    dphi = np.zeros((m, 3, 3))
    dphi[:, 0, :2] = -P @ dn
    dphi[:, 0, 2] = 1.0
    dphi[:, 1:, :2] = E @ dn
    return r, dp, dw, dphi


@dataclass(frozen=True, eq=False)
class FlushContact(Artefact):
    """Poses of a face of the measured frame pressed flush against one plane.

    The ``flush`` artefact kind: three residuals per pose (height, two tilts); no own
    unknowns; the plane's ``"<plane>.n1"``, ``"<plane>.n2"`` [rad] and ``"<plane>.d"``
    [m] shared by every dataset of the same plane.

    Attributes:
        q_act: (m, n_act) actuator values [m, rad].
        actuated: actuated joint names (columns of ``q_act``).
        frame: the measured frame (its origin on the face).
        plane: the plane's name (datasets naming the same plane share it).
        axis: (3,) the face's normal in the measured frame (unit after reading).
        normal: (3,) the plane's approximate normal in the world (root) frame, the way
            ``axis`` points at contact (within ~45° of the truth).
        std_height: 1σ of a touch's height [m] (> 0).
        std_tilt: 1σ of each tilt [rad] (> 0).

    Raises:
        MeasurementError: shapes, non-finite values, a zero axis or normal, σ ≤ 0.
    """

    q_act: np.ndarray
    actuated: tuple[str, ...]
    frame: str
    plane: str = "table"
    axis: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    normal: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    std_height: float = 2e-4
    std_tilt: float = 2e-3

    kind: ClassVar[str] = "flush"
    description: ClassVar[str] = "a face of the measured frame flush against an unknown plane"
    dim: ClassVar[int] = 3

    def __post_init__(self) -> None:
        q = np.atleast_2d(np.asarray(self.q_act, dtype=float))
        object.__setattr__(self, "actuated", tuple(str(a) for a in self.actuated))
        if q.ndim != 2 or q.shape[1] != len(self.actuated) or not np.all(np.isfinite(q)):
            raise MeasurementError(
                f"flush contact q_act must be finite, (m, {len(self.actuated)}) for the "
                f"joints {list(self.actuated)}, got shape {q.shape}"
            )
        object.__setattr__(self, "q_act", q)
        object.__setattr__(self, "axis", _unit(self.axis, "the face's axis"))
        object.__setattr__(self, "normal", _unit(self.normal, "the plane's normal"))
        for what, v in (("std_height [m]", self.std_height), ("std_tilt [rad]", self.std_tilt)):
            if not (np.isfinite(v) and v > 0):
                raise MeasurementError(f"flush contact {what} must be finite and > 0, got {v}")
        if not str(self.plane).strip():
            raise MeasurementError("a flush contact names its plane (e.g. 'table')")

    def __len__(self) -> int:
        return len(self.q_act)

    @property
    def sigma(self) -> np.ndarray:
        return np.tile([self.std_height, self.std_tilt, self.std_tilt], (len(self), 1))

    @property
    def shared_names(self) -> tuple[str, ...]:
        return (f"{self.plane}.n1", f"{self.plane}.n2", f"{self.plane}.d")

    def residuals(
        self, P: np.ndarray, Rs: np.ndarray, theta: np.ndarray, phi: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        r, dp, dw, dphi = flush_residuals(
            np.asarray(P), np.asarray(Rs), self.axis, self.normal, np.asarray(phi)
        )
        return r, dp, dw, np.zeros((len(self), 3, 0)), dphi

    @classmethod
    def shared_terms(cls, datasets: Sequence[Artefact]) -> SharedTerms:
        return _Planes(datasets)


class _Planes(SharedTerms):
    """The planes of the flush datasets of one problem: (n1, n2, d) each, started from data."""

    def __init__(self, datasets: Sequence[Artefact]) -> None:
        super().__init__(datasets)
        self.units = tuple("m" if n.endswith(".d") else "rad" for n in self.names)
        normals: dict[str, np.ndarray] = {}
        for d in self.datasets:
            assert isinstance(d, FlushContact)
            seen = normals.setdefault(d.plane, d.normal)
            if not np.allclose(seen, d.normal):
                raise MeasurementError(
                    f"flush contacts of plane {d.plane!r} declare different normals "
                    f"{list(seen)} and {list(d.normal)}; give the plane one normal"
                )

    def start(
        self, poses: Sequence[tuple[np.ndarray, np.ndarray]], thetas: Sequence[np.ndarray]
    ) -> np.ndarray:
        """Tilts from the mean face normal, offset from the mean height (nominal poses)."""
        phi = np.zeros(len(self.names))
        where = {n: i for i, n in enumerate(self.names)}
        for plane in dict.fromkeys(d.plane for d in self.datasets):  # type: ignore[attr-defined]
            mine = [(d, pose) for d, pose in zip(self.datasets, poses, strict=True)
                    if d.plane == plane]  # type: ignore[attr-defined]  # fmt: skip
            d0 = mine[0][0]
            faces = np.vstack([Rs @ d.axis for d, (_, Rs) in mine])  # type: ignore[attr-defined]
            u = faces.mean(axis=0)
            n0 = d0.normal  # type: ignore[attr-defined]
            e1, e2 = plane_basis(n0)
            if u @ n0 > 0.5 * np.linalg.norm(u):  # the faces agree with the declared side
                phi[where[f"{plane}.n1"]] = (u @ e1) / (u @ n0)
                phi[where[f"{plane}.n2"]] = (u @ e2) / (u @ n0)
            n, _ = _normal(n0, phi[[where[f"{plane}.n1"], where[f"{plane}.n2"]]])
            phi[where[f"{plane}.d"]] = float(np.mean(np.vstack([P for _, (P, _) in mine]) @ n))
        return phi
