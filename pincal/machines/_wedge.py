"""Closed-form kinematics of the 3-axis wedge mechanism of seed 002 (patent CN, 2021).

The mechanism moves in the world XZ plane. Three coaxial linear motors run on one X
guide: ``q0`` carries a vertical (Z) guide on which the centre of a rigid bar slides;
``q1`` and ``q2`` carry two wedges whose inclined walls face each other (a shallow V).
Each bar end is hinged to a shoe that slides along its wedge's inclined wall. Outputs:
the bar-centre position ``x``, ``z`` and the bar angle ``α``.

With the effective motor positions ``Q_i = q_i + dq_i`` (``dq_i`` = zero offsets) the
constraint equations are, in the patent's form,

    f0 = x − Q0                                         = 0
    f1 = z − l1 sinα + k1 (Q0 − l1 cosα + l1 − Q1)      = 0   (bar end 1 on wedge 1)
    f2 = z + l2 sinα − k2 (Q0 + l2 cosα − l2 − Q2)      = 0   (bar end 2 on wedge 2)

Geometric reading: the bar direction is (cosα, sinα) in (x, z); bar end 1 is at
(x − l1 cosα, z − l1 sinα), bar end 2 at (x + l2 cosα, z + l2 sinα). Wedge 1's wall is
the line through (Q1 − l1, 0) with slope −k1, wedge 2's the line through (Q2 + l2, 0)
with slope +k2. Hence the home pose x = z = α = 0 is reached at q0 = q1 = q2 = 0 (no
offsets). The patent writes ``q0`` (not ``x``) inside f1 and f2; on the solution set
``x = Q0`` so both readings give the same kinematics. Here the patent form is used, so
∂f1/∂x = ∂f2/∂x = 0 and the offset ``dq0`` appears in all three rows, as in the
patent's structural error vector.

Units: lengths [m], angles [rad], slopes k [-] (dimensionless, dz/dx).
Pose arrays have columns ``(x, z, α)``; joint arrays ``(q0, q1, q2)``. Leading batch
dimensions are allowed everywhere: shape (3,) or (m, 3).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import ClassVar

import numpy as np

from pincal.errors import ClosureError, ParameterError

__all__ = [
    "WedgeConstraintJacobians",
    "WedgeGeometry",
    "as_rows",
    "wedge_constraint_jacobians",
    "wedge_constraints",
    "wedge_forward",
    "wedge_inverse",
]


@dataclass(frozen=True)
class WedgeGeometry:
    """Geometric parameters of the wedge mechanism (the patent's calibrated set).

    Attributes:
        l1: distance bar centre → hinge of bar end 1 [m].
        l2: distance bar centre → hinge of bar end 2 [m].
        k1: slope of wedge 1's inclined wall [-] (the wall is z = −k1 (x − x_ref1)).
        k2: slope of wedge 2's inclined wall [-] (the wall is z = +k2 (x − x_ref2)).
        dq0: zero offset of motor q0 [m]; the effective position is q0 + dq0.
        dq1: zero offset of motor q1 [m].
        dq2: zero offset of motor q2 [m].
    """

    l1: float
    l2: float
    k1: float
    k2: float
    dq0: float = 0.0
    dq1: float = 0.0
    dq2: float = 0.0

    PARAMETER_NAMES: ClassVar[tuple[str, ...]] = ("l1", "l2", "k1", "k2", "dq0", "dq1", "dq2")

    def __post_init__(self) -> None:
        values = [getattr(self, f.name) for f in fields(self)]
        if not np.all(np.isfinite(values)):
            raise ParameterError(f"wedge geometry values must be finite, got {values}")
        if self.l1 <= 0.0 or self.l2 <= 0.0:
            raise ParameterError(f"bar half-lengths must be > 0 m, got l1={self.l1}, l2={self.l2}")
        if self.k1 == 0.0 or self.k2 == 0.0:
            raise ParameterError(f"wedge slopes must be non-zero, got k1={self.k1}, k2={self.k2}")

    @classmethod
    def nominal(cls) -> WedgeGeometry:
        """The nominal machine used by models/wedge3: l1 = l2 = 100 mm, k1 = k2 = 0.2."""
        return cls(l1=0.1, l2=0.1, k1=0.2, k2=0.2)

    def as_vector(self) -> np.ndarray:
        """Parameters as a (7,) array in the order of ``PARAMETER_NAMES``."""
        return np.array([getattr(self, n) for n in self.PARAMETER_NAMES], dtype=float)

    @classmethod
    def from_vector(cls, values: np.ndarray) -> WedgeGeometry:
        """Inverse of :meth:`as_vector`; ``values`` has shape (7,)."""
        values = np.asarray(values, dtype=float)
        if values.shape != (7,):
            raise ParameterError(
                f"wedge parameter vector must have shape (7,) {cls.PARAMETER_NAMES}, "
                f"got {values.shape}"
            )
        return cls(**dict(zip(cls.PARAMETER_NAMES, values.tolist(), strict=True)))


@dataclass(frozen=True)
class WedgeConstraintJacobians:
    """Analytic Jacobians of :func:`wedge_constraints` (rows f0, f1, f2).

    Attributes:
        d_pose: ∂f/∂(x, z, α), shape (..., 3, 3).
        d_q: ∂f/∂(q0, q1, q2), shape (..., 3, 3).
        d_params: ∂f/∂(l1, l2, k1, k2, dq0, dq1, dq2), shape (..., 3, 7).
    """

    d_pose: np.ndarray
    d_q: np.ndarray
    d_params: np.ndarray


def as_rows(a: np.ndarray, what: str) -> np.ndarray:
    """``a`` as a float array whose last axis has length 3: shape (3,) or (m, 3).

    Raises:
        ParameterError: the last axis is not of length 3 (``what`` names the argument).
    """
    a = np.asarray(a, dtype=float)
    if a.shape[-1:] != (3,):
        raise ParameterError(f"{what} must have shape (3,) or (m, 3), got {a.shape}")
    return a


def _effective_q(q: np.ndarray, geom: WedgeGeometry) -> tuple[np.ndarray, ...]:
    return q[..., 0] + geom.dq0, q[..., 1] + geom.dq1, q[..., 2] + geom.dq2


def wedge_constraints(q: np.ndarray, pose: np.ndarray, geom: WedgeGeometry) -> np.ndarray:
    """Constraint residuals (f0, f1, f2) of the patent's equations.

    Args:
        q: motor positions (q0, q1, q2) [m], shape (3,) or (m, 3).
        pose: outputs (x [m], z [m], α [rad]), same leading shape as ``q``.
        geom: geometric parameters.

    Returns:
        Residuals [m], shape (3,) or (m, 3); zero when the mechanism is assembled.
    """
    q = as_rows(q, "q")
    pose = as_rows(pose, "pose")
    Q0, Q1, Q2 = _effective_q(q, geom)
    x, z, a = pose[..., 0], pose[..., 1], pose[..., 2]
    c, s = np.cos(a), np.sin(a)
    f0 = x - Q0
    f1 = z - geom.l1 * s + geom.k1 * (Q0 - geom.l1 * c + geom.l1 - Q1)
    f2 = z + geom.l2 * s - geom.k2 * (Q0 + geom.l2 * c - geom.l2 - Q2)
    return np.stack([f0, f1, f2], axis=-1)


def wedge_forward(q: np.ndarray, geom: WedgeGeometry) -> np.ndarray:
    """Closed-form forward kinematics: motor positions → (x, z, α).

    Subtracting f2 from f1 eliminates z and leaves

        b sinα + a cosα = r,   b = l1 + l2,   a = k1 l1 − k2 l2,
        r = k1 (Q0 + l1 − Q1) + k2 (Q0 − l2 − Q2),

    i.e. R sin(α + φ) = r with R = √(a² + b²), φ = atan2(a, b). The two solutions are
    α = asin(r/R) − φ and α = π − asin(r/R) − φ; the second one turns the bar over
    (end 1 on the right), which the hinges and wedges do not allow, so the branch near
    α = 0 (|α + φ| ≤ π/2) is returned. Then z = l1 sinα − k1 (Q0 − l1 cosα + l1 − Q1)
    and x = Q0.

    Args:
        q: motor positions (q0, q1, q2) [m], shape (3,) or (m, 3).
        geom: geometric parameters.

    Returns:
        Pose (x [m], z [m], α [rad]), shape (3,) or (m, 3).

    Raises:
        ClosureError: if |r| > R for some row (the bar cannot reach both wedges).
    """
    q = as_rows(q, "q")
    Q0, Q1, Q2 = _effective_q(q, geom)
    l1, l2, k1, k2 = geom.l1, geom.l2, geom.k1, geom.k2
    b = l1 + l2
    a = k1 * l1 - k2 * l2
    R = np.hypot(a, b)
    r = k1 * (Q0 + l1 - Q1) + k2 * (Q0 - l2 - Q2)
    ratio = np.atleast_1d(r / R)
    bad = np.flatnonzero(np.abs(ratio) > 1.0)
    if bad.size:
        i = int(bad[0])
        raise ClosureError(
            f"wedge mechanism cannot be assembled at pose {i}: |r|/R = {abs(ratio[i]):.6g} > 1"
        )
    alpha = np.arcsin(np.clip(r / R, -1.0, 1.0)) - np.arctan2(a, b)
    z = l1 * np.sin(alpha) - k1 * (Q0 - l1 * np.cos(alpha) + l1 - Q1)
    return np.stack([Q0, z, alpha], axis=-1)


def wedge_inverse(pose: np.ndarray, geom: WedgeGeometry) -> np.ndarray:
    """Closed-form inverse kinematics: (x, z, α) → motor positions (q0, q1, q2).

    Q0 = x, Q1 = x − l1 cosα + l1 + (z − l1 sinα)/k1,
    Q2 = x + l2 cosα − l2 − (z + l2 sinα)/k2, then q_i = Q_i − dq_i.

    Args:
        pose: (x [m], z [m], α [rad]), shape (3,) or (m, 3).
        geom: geometric parameters.

    Returns:
        Motor positions [m], shape (3,) or (m, 3).
    """
    pose = as_rows(pose, "pose")
    x, z, a = pose[..., 0], pose[..., 1], pose[..., 2]
    c, s = np.cos(a), np.sin(a)
    Q1 = x - geom.l1 * c + geom.l1 + (z - geom.l1 * s) / geom.k1
    Q2 = x + geom.l2 * c - geom.l2 - (z + geom.l2 * s) / geom.k2
    return np.stack([x - geom.dq0, Q1 - geom.dq1, Q2 - geom.dq2], axis=-1)


def wedge_constraint_jacobians(
    q: np.ndarray, pose: np.ndarray, geom: WedgeGeometry
) -> WedgeConstraintJacobians:
    """Analytic Jacobians of :func:`wedge_constraints` wrt pose, motors and parameters.

    Args:
        q: motor positions [m], shape (3,) or (m, 3).
        pose: (x, z, α) [m, m, rad], same leading shape.
        geom: geometric parameters.

    Returns:
        The three Jacobians; see :class:`WedgeConstraintJacobians` for shapes and units.
    """
    q = as_rows(q, "q")
    pose = as_rows(pose, "pose")
    batch = np.broadcast_shapes(q.shape[:-1], pose.shape[:-1])
    Q0, Q1, Q2 = _effective_q(q, geom)
    a = pose[..., 2]
    c, s = np.cos(a), np.sin(a)
    l1, l2, k1, k2 = geom.l1, geom.l2, geom.k1, geom.k2
    zero = np.zeros(batch)
    one = np.ones(batch)

    def mat(rows: list[list]) -> np.ndarray:
        return np.stack(
            [np.stack([np.broadcast_to(v, batch) for v in row], -1) for row in rows], -2
        )

    d_pose = mat(
        [
            [one, zero, zero],
            [zero, one, -l1 * c + k1 * l1 * s],
            [zero, one, l2 * c + k2 * l2 * s],
        ]
    )
    d_q = mat(
        [
            [-one, zero, zero],
            [k1 * one, -k1 * one, zero],
            [-k2 * one, zero, k2 * one],
        ]
    )
    # parameter order: l1, l2, k1, k2, dq0, dq1, dq2 (offsets act like the motors)
    d_params = mat(
        [
            [zero, zero, zero, zero, -one, zero, zero],
            [-s + k1 * (1.0 - c), zero, Q0 - l1 * c + l1 - Q1, zero, k1 * one, -k1 * one, zero],
            [zero, s - k2 * (c - 1.0), zero, -(Q0 + l2 * c - l2 - Q2), -k2 * one, zero, k2 * one],
        ]
    )
    return WedgeConstraintJacobians(d_pose=d_pose, d_q=d_q, d_params=d_params)
