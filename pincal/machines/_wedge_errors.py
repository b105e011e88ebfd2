"""Error-mapping matrices, global sensitivity and compensation of the wedge mechanism.

The closed-form kinematics they differentiate are in :mod:`pincal.machines._wedge`;
units and array conventions are those of that module: lengths [m], angles [rad],
slopes [-]; poses (x, z, α), motors (q0, q1, q2), shape (3,) or (m, 3).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from pincal.errors import ParameterError
from pincal.machines._wedge import (
    WedgeGeometry,
    as_rows,
    wedge_constraint_jacobians,
    wedge_forward,
    wedge_inverse,
)

__all__ = [
    "PATENT_ERROR_NAMES",
    "PATENT_PRESET_NAMES",
    "WedgeSensitivity",
    "wedge_compensation",
    "wedge_error_matrix",
    "wedge_global_sensitivity",
    "wedge_patent_error_matrix",
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
        x_range: (min, max) of the x coordinate [m].
        z_range: (min, max) of the z coordinate [m].
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
    poses = np.atleast_2d(as_rows(poses, "poses"))
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
