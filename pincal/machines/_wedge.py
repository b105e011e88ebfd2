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
from typing import ClassVar, Literal

import numpy as np

from pincal.errors import ClosureError, ParameterError

__all__ = [
    "PATENT_ERROR_NAMES",
    "PATENT_PRESET_NAMES",
    "WedgeConstraintJacobians",
    "WedgeGeometry",
    "WedgeSensitivity",
    "wedge_compensation",
    "wedge_constraint_jacobians",
    "wedge_constraints",
    "wedge_error_matrix",
    "wedge_forward",
    "wedge_global_sensitivity",
    "wedge_inverse",
    "wedge_patent_error_matrix",
    "wedge_urdf",
    "wedge_workspace_grid",
]

#: Names of the 12 entries of the patent's structural error vector
#: δd = [δq0, 0, 0, 0, δq0, δq1, δl1, δk1, δq0, δq2, δl2, δk2] (one block of four per
#: constraint row f0, f1, f2; entries 2..4 are structurally zero).
PATENT_ERROR_NAMES: tuple[str, ...] = (
    "f0.dq0",
    "f0.zero2",
    "f0.zero3",
    "f0.zero4",
    "f1.dq0",
    "f1.dq1",
    "f1.l1",
    "f1.k1",
    "f2.dq0",
    "f2.dq2",
    "f2.l2",
    "f2.k2",
)


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


@dataclass(frozen=True)
class WedgeSensitivity:
    """Global sensitivity indices of the error-mapping matrix columns.

    Attributes:
        names: column names (``PATENT_ERROR_NAMES`` or ``WedgeGeometry.PARAMETER_NAMES``).
        position: mean over the workspace of the Euclidean norm of the position rows
            (δx, δz) of each column, shape (k,) [m per unit of the parameter].
        orientation: mean over the workspace of |δα| of each column, shape (k,)
            [rad per unit of the parameter].
        n_samples: number of workspace samples averaged.
    """

    names: tuple[str, ...]
    position: np.ndarray
    orientation: np.ndarray
    n_samples: int


def _as_rows(a: np.ndarray, what: str) -> np.ndarray:
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
    q = _as_rows(q, "q")
    pose = _as_rows(pose, "pose")
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
    q = _as_rows(q, "q")
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
    pose = _as_rows(pose, "pose")
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
    q = _as_rows(q, "q")
    pose = _as_rows(pose, "pose")
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


def wedge_error_matrix(q: np.ndarray, geom: WedgeGeometry) -> np.ndarray:
    """Identification Jacobian d(x, z, α)/d(l1, l2, k1, k2, dq0, dq1, dq2) at fixed motors.

    By the implicit function theorem, dpose/dp = −(∂f/∂pose)⁻¹ ∂f/∂p, evaluated at the
    forward-kinematics solution of ``q``.

    Args:
        q: motor positions [m], shape (3,) or (m, 3).
        geom: geometric parameters.

    Returns:
        Shape (3, 7) or (m, 3, 7); rows (x [m], z [m], α [rad]) per unit parameter.
    """
    pose = wedge_forward(q, geom)
    jac = wedge_constraint_jacobians(q, pose, geom)
    return -np.linalg.solve(jac.d_pose, jac.d_params)


def wedge_patent_error_matrix(q: np.ndarray, geom: WedgeGeometry) -> np.ndarray:
    """The patent's error-mapping matrix J with δX = J δd, δd in ``PATENT_ERROR_NAMES``.

    Each entry of δd perturbs one constraint row only: column (row r, parameter p) is
    −(∂f/∂pose)⁻¹ e_r ∂f_r/∂p. Columns 2..4 (the zeros of δd) are zero. Summing the
    three δq0 columns (1, 5, 9) gives the dq0 column of :func:`wedge_error_matrix`.

    Args:
        q: motor positions [m], shape (3,) or (m, 3).
        geom: geometric parameters.

    Returns:
        Shape (3, 12) or (m, 3, 12).
    """
    pose = wedge_forward(q, geom)
    jac = wedge_constraint_jacobians(q, pose, geom)
    inv = np.linalg.inv(jac.d_pose)  # (..., 3, 3)
    P = jac.d_params
    # (row, parameter index in WedgeGeometry order) for each δd entry; None = zero entry
    layout = [
        (0, 4),
        None,
        None,
        None,
        (1, 4),
        (1, 5),
        (1, 0),
        (1, 2),
        (2, 4),
        (2, 6),
        (2, 1),
        (2, 3),
    ]
    cols = []
    for entry in layout:
        if entry is None:
            cols.append(np.zeros(inv.shape[:-1]))
        else:
            row, k = entry
            cols.append(-inv[..., :, row] * P[..., row, k][..., None])
    return np.stack(cols, axis=-1)


def wedge_workspace_grid(
    x_range: tuple[float, float],
    z_range: tuple[float, float],
    alpha_range: tuple[float, float],
    n: int = 7,
) -> np.ndarray:
    """Regular n×n×n grid of poses over a box of the output space (x, z, α).

    Args:
        x_range, z_range: (min, max) [m].
        alpha_range: (min, max) [rad].
        n: points per axis (≥ 1).

    Returns:
        Poses, shape (n³, 3).
    """
    if n < 1:
        raise ParameterError(f"grid size n must be >= 1, got {n}")
    axes = [np.linspace(lo, hi, n) for lo, hi in (x_range, z_range, alpha_range)]
    return np.stack([g.ravel() for g in np.meshgrid(*axes, indexing="ij")], axis=-1)


def wedge_global_sensitivity(
    geom: WedgeGeometry,
    poses: np.ndarray,
    columns: Literal["patent", "parameters"] = "patent",
) -> WedgeSensitivity:
    """Global sensitivity of each error-mapping column over a workspace sample.

    Reference implementation of the index described in models/wedge3/README.md: the
    workspace integral ∫_W s_k dW / ∫_W dW of the local sensitivity is estimated by the
    mean over ``poses`` (uniform samples or a regular grid of the (x, z, α) box), with
    local position sensitivity s_k = √(J_xk² + J_zk²) and orientation sensitivity
    s_k = |J_αk|.

    Args:
        geom: geometric parameters.
        poses: workspace poses (x, z, α), shape (m, 3); motors come from the inverse.
        columns: ``"patent"`` for the 12 δd columns, ``"parameters"`` for the 7
            physical parameters of :class:`WedgeGeometry`.

    Returns:
        The sensitivity indices per column.
    """
    poses = np.atleast_2d(_as_rows(poses, "poses"))
    q = wedge_inverse(poses, geom)
    if columns == "patent":
        J = wedge_patent_error_matrix(q, geom)
        names = PATENT_ERROR_NAMES
    elif columns == "parameters":
        J = wedge_error_matrix(q, geom)
        names = WedgeGeometry.PARAMETER_NAMES
    else:
        raise ParameterError(f"columns must be 'patent' or 'parameters', got {columns!r}")
    position = np.mean(np.linalg.norm(J[:, :2, :], axis=1), axis=0)
    orientation = np.mean(np.abs(J[:, 2, :]), axis=0)
    return WedgeSensitivity(
        names=names, position=position, orientation=orientation, n_samples=poses.shape[0]
    )


def _fmt(v: float) -> str:
    return f"{v:.12g}"


def wedge_urdf(geom: WedgeGeometry, name: str = "wedge3") -> str:
    """URDF text of the spanning tree realising ``geom`` exactly (see models/wedge3).

    The offsets dq_i go into the x position of the motor joints' origins, l1 and l2
    into the bar-end joints and (with the patent's coupling) the wedge wall reference
    points, k1 and k2 into the pitch of the wedge slide joints: pitch1 = atan(k1),
    pitch2 = −atan(k2).

    Args:
        geom: geometric parameters.
        name: robot name.

    Returns:
        The URDF document as a string.
    """
    l1, l2 = geom.l1, geom.l2
    p1, p2 = np.arctan(geom.k1), -np.arctan(geom.k2)
    half = 0.5 * (l1 + l2)
    w = 0.02  # visual thickness [m]

    def box(size: tuple[float, float, float], xyz=(0.0, 0.0, 0.0), rgba="0.6 0.6 0.6 1") -> str:
        sx, sy, sz = (_fmt(v) for v in size)
        ox, oy, oz = (_fmt(v) for v in xyz)
        return (
            f'<visual><origin xyz="{ox} {oy} {oz}" rpy="0 0 0"/>'
            f'<geometry><box size="{sx} {sy} {sz}"/></geometry>'
            f'<material name="rgba {rgba}"><color rgba="{rgba}"/></material></visual>'
        )

    def hinge(rgba: str = "0.2 0.2 0.2 1") -> str:
        return (
            '<visual><origin xyz="0 0 0" rpy="1.5707963267948966 0 0"/>'
            f'<geometry><cylinder radius="{_fmt(0.3 * w)}" length="{_fmt(1.5 * w)}"/></geometry>'
            f'<material name="rgba {rgba}"><color rgba="{rgba}"/></material></visual>'
        )

    def link(lname: str, visual: str = "") -> str:
        return (
            f'  <link name="{lname}">{visual}<inertial><mass value="0.1"/>'
            '<origin xyz="0 0 0"/><inertia ixx="1e-5" ixy="0" ixz="0" iyy="1e-5" iyz="0" '
            'izz="1e-5"/></inertial></link>\n'
        )

    def joint(
        jname: str,
        jtype: str,
        parent: str,
        child: str,
        xyz=(0.0, 0.0, 0.0),
        rpy=(0.0, 0.0, 0.0),
        axis=None,
        limit=None,
    ) -> str:
        s = (
            f'  <joint name="{jname}" type="{jtype}"><parent link="{parent}"/>'
            f'<child link="{child}"/><origin xyz="{" ".join(_fmt(v) for v in xyz)}" '
            f'rpy="{" ".join(_fmt(v) for v in rpy)}"/>'
        )
        if axis is not None:
            s += f'<axis xyz="{" ".join(_fmt(v) for v in axis)}"/>'
        if limit is not None:
            s += (
                f'<limit lower="{_fmt(limit[0])}" upper="{_fmt(limit[1])}" '
                'effort="100" velocity="1"/>'
            )
        return s + "</joint>\n"

    grey, blue, orange, green = "0.5 0.5 0.5 1", "0.2 0.4 0.8 1", "0.9 0.5 0.1 1", "0.2 0.7 0.3 1"
    out = [
        f'<?xml version="1.0"?>\n<!-- Generated by pincal.machines.wedge_urdf({geom!r}).\n'
        "     Lengths in m, angles in rad. See models/wedge3/README.md. -->\n"
        f'<robot name="{name}">\n'
    ]
    out.append(link("world", box((4 * half, 2 * w, 0.5 * w), (0, 0, -3 * w), grey)))
    # motor q0 -> vertical guide -> bar revolute -> bar
    out.append(
        joint(
            "q0",
            "prismatic",
            "world",
            "carriage0",
            (geom.dq0, 0, 0),
            axis=(1, 0, 0),
            limit=(-0.1, 0.1),
        )
    )
    out.append(link("carriage0", box((w, w, 2 * w), (0, -w, 0), blue)))
    out.append(
        joint(
            "z_guide", "prismatic", "carriage0", "bar_slider", axis=(0, 0, 1), limit=(-0.05, 0.05)
        )
    )
    out.append(link("bar_slider", hinge()))
    out.append(
        joint("bar_rev", "revolute", "bar_slider", "bar", axis=(0, -1, 0), limit=(-0.5, 0.5))
    )
    out.append(link("bar", box((l1 + l2, 0.5 * w, 0.3 * w), (0.5 * (l2 - l1), 0, 0), orange)))
    out.append(joint("bar_centre_frame", "fixed", "bar", "bar_centre"))
    out.append(link("bar_centre"))
    out.append(joint("bar_end1_frame", "fixed", "bar", "bar_end1", (-l1, 0, 0)))
    out.append(link("bar_end1", hinge()))
    out.append(joint("bar_end2_frame", "fixed", "bar", "bar_end2", (l2, 0, 0)))
    out.append(link("bar_end2", hinge()))
    # wedges: motor -> slide along the inclined wall (pitch = wall angle)
    for i, (dq, x_ref, pitch) in enumerate(((geom.dq1, -l1, p1), (geom.dq2, l2, p2)), start=1):
        wall_len = 0.6 * half
        out.append(
            joint(
                f"q{i}",
                "prismatic",
                "world",
                f"wedge{i}",
                (dq, 0, 0),
                axis=(1, 0, 0),
                limit=(-0.1, 0.1),
            )
        )
        out.append(link(f"wedge{i}"))
        out.append(
            joint(
                f"wedge{i}_slide",
                "prismatic",
                f"wedge{i}",
                f"wedge{i}_shoe",
                (x_ref, 0, 0),
                (0, pitch, 0),
                axis=(1, 0, 0),
                limit=(-0.05, 0.05),
            )
        )
        out.append(link(f"wedge{i}_shoe", box((0.3 * w, w, 0.2 * w), (0, 0, 0), blue)))
        # visual of the wedge wall: a slab below the wall line, in the wall frame
        out.append(
            joint(
                f"wedge{i}_wall_frame",
                "fixed",
                f"wedge{i}",
                f"wedge{i}_wall",
                (x_ref, 0, 0),
                (0, pitch, 0),
            )
        )
        out.append(
            link(f"wedge{i}_wall", box((wall_len, 1.5 * w, 0.5 * w), (0, 0, -0.25 * w), green))
        )
    out.append("</robot>\n")
    return "".join(out)


#: Names of the seven parameters of the ``patent`` preset of models/wedge3.
PATENT_PRESET_NAMES: tuple[str, ...] = (
    "q0.offset",
    "q1.offset",
    "q2.offset",
    "bar_end1_frame.tx",
    "bar_end2_frame.tx",
    "wedge1_slide.ry",
    "wedge2_slide.ry",
)


def wedge_compensation(
    names: tuple[str, ...] | list[str],
    values: np.ndarray,
    nominal: WedgeGeometry | None = None,
) -> WedgeGeometry:
    """Compensated geometry (the patent's capital-letter parameters) from preset values.

    Exact map of models/wedge3/README.md ("Preset patent"): ``δl1 = −bar_end1_frame.tx``,
    ``δl2 = bar_end2_frame.tx``, ``dq0 = q0.offset``, ``dq1 = q1.offset + δl1``,
    ``dq2 = q2.offset − δl2``, ``k1 = tan(atan k1⁰ + wedge1_slide.ry)``,
    ``k2 = tan(atan k2⁰ − wedge2_slide.ry)``. The result has the nominal structure, so
    :func:`wedge_forward` / :func:`wedge_inverse` remain the calibrated machine's exact
    kinematics.

    Args:
        names: parameter names (any subset of ``PATENT_PRESET_NAMES``; others rejected).
        values: values [m, rad], same length as ``names``.
        nominal: the geometry the preset perturbs (default ``WedgeGeometry.nominal()``).
    """
    nominal = nominal or WedgeGeometry.nominal()
    values = np.asarray(values, dtype=float)
    if values.shape != (len(names),):
        raise ParameterError(f"expected {len(names)} values, got shape {values.shape}")
    unknown = [n for n in names if n not in PATENT_PRESET_NAMES]
    if unknown:
        raise ParameterError(
            f"parameters {unknown} have no patent meaning; valid: {list(PATENT_PRESET_NAMES)}"
        )
    v = dict.fromkeys(PATENT_PRESET_NAMES, 0.0) | dict(zip(names, values.tolist(), strict=True))
    dl1, dl2 = -v["bar_end1_frame.tx"], v["bar_end2_frame.tx"]
    return WedgeGeometry(
        l1=nominal.l1 + dl1,
        l2=nominal.l2 + dl2,
        k1=float(np.tan(np.arctan(nominal.k1) + v["wedge1_slide.ry"])),
        k2=float(np.tan(np.arctan(nominal.k2) - v["wedge2_slide.ry"])),
        dq0=nominal.dq0 + v["q0.offset"],
        dq1=nominal.dq1 + v["q1.offset"] + dl1,
        dq2=nominal.dq2 + v["q2.offset"] - dl2,
    )
