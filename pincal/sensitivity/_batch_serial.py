"""The batched identification Jacobian of a serial chain (no closures), column-wise.

Split from :mod:`pincal.sensitivity._batch_jacobian` (same mathematics, a faster
formation for chains): each parameterised joint origin j is ``oMi[parent_j] · (R0_j,
p0_j)``; its local twist per parameter moves and turns the measured frame by one GEMM per
joint over all poses.
"""

from __future__ import annotations

import numpy as np

from pincal.model._batch import BatchKinematics, cross_cols, mm, mv
from pincal.model._mechanism import Mechanism
from pincal.model._parameters import ParameterSet
from pincal.sensitivity._jacobian import _Plan

__all__: list[str] = []


def _mmc(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """``A @ B`` of stacked matrices A (…, r, m) by one constant matrix B (m, k) (one GEMM)."""
    A = np.ascontiguousarray(A)
    return (A.reshape(-1, A.shape[-1]) @ B).reshape(*A.shape[:-1], B.shape[1])


def _columns(cols: np.ndarray) -> slice | np.ndarray:
    """A slice for contiguous parameter columns (faster to write), else the indices."""
    if cols.size and np.all(np.diff(cols) == 1):
        return slice(int(cols[0]), int(cols[-1]) + 1)
    return cols


def _anchors(
    mech: Mechanism, plan: _Plan
) -> tuple[list[str], np.ndarray, np.ndarray, np.ndarray]:
    """Parameterised joints, their origins' parent joints (J,) and constant placements.

    Origin j = ``oMi[parent_j] · (R0_j, p0_j)`` with R0 (J, 3, 3), p0 (J, 3) [m].
    """
    model, names = mech.model, list(plan.origins)
    parents, R0, p0 = [], [], []
    for j in names:
        fid, jid, parent = plan.origins[j]
        M = model.frames[fid].placement if fid >= 0 else model.jointPlacements[jid]
        parents.append(model.frames[fid].parentJoint if fid >= 0 else parent)
        R0.append(M.rotation)
        p0.append(M.translation)
    return names, np.array(parents, dtype=int), np.array(R0), np.array(p0)


def _serial_path(
    mech: Mechanism,
    params: ParameterSet,
    bk: BatchKinematics,
    values: np.ndarray,
    plan: _Plan,
    out: np.ndarray | None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`_world_path` of a chain without closures, column-wise.

    The local twist ``[v; ω] = eff_j[:, k]`` of origin j (world rotation R_o = R_p R0_j,
    position p_o) moves the measured frame's origin by ``R_o v + (R_o ω) × (p_m − p_o)``
    and turns it by ``R_mᵀ R_o ω`` (local): ``R_p · (R0_j [v | ω])`` of all poses is one
    GEMM per joint, the cross products and the rotation into the measured frame are
    formed for all n columns at once.
    """
    N, n = bk.q.shape[0], len(params)
    Rm, pm = mech.batch_model.frame_placement(bk, mech.frame_id(mech.measured_frame))
    twists = params.joint_twists(values)
    moves = set(plan.moves[mech.measured_frame])
    names, parents, R0, p0 = _anchors(mech, plan)
    J = np.zeros((N, 6, n)) if out is None else out
    Rmt = np.swapaxes(Rm, 1, 2)
    for i, j in enumerate(names):  # small temporaries per joint (no large fresh arrays)
        if j not in moves:
            continue
        cols, _, eff = twists[j]
        c, k = _columns(cols), cols.size
        Rp = bk.rotations[:, parents[i]]
        G = _mmc(Rp, R0[i] @ np.concatenate([eff[:3], eff[3:]], axis=1))
        d = pm - bk.translations[:, parents[i]] - mv(Rp, p0[i])  # p_m − p_o
        J[:, :3, c] = G[..., :k] + cross_cols(G[..., k:], d[:, :, None])
        J[:, 3:, c] = mm(Rmt, G[..., k:])
    return Rm, pm, J
