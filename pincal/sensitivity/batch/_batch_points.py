"""The identification Jacobian of N poses of a machine closed by point closures only.

Stewart platforms, hexapods with sliders, PRS/RPR legs: every loop is cut at a ball
joint, ``p_b = p_a`` in world axes. There the whole Jacobian is a few dense products:

* every parameter column k (of joint j) displaces j's origin by a constant local twist
  ``eff_j[:, k]``; in world axes, taken at the world origin, that is the twist
  ``W_k = R_o ω``, ``V_k = R_o v + p_o × W_k`` (one GEMM per group of joints with as
  many parameters, all poses at once: arrays (N, 3, n));
* a world point x fixed to a moved body moves by ``V + W × x``, so the measured frame
  moves by ``[V + W × p_m; R_mᵀ W]`` on the columns of the joints below it, and a point
  closure ``p_b − p_a`` by ``∂c/∂p = (s_b − s_a) V + W × (s_b p_b − s_a p_a)``
  (s = 1 for the joints below that frame);
* the passive joints re-close the loops: ``J −= Yᵀ ∂c/∂p`` with the adjoint
  ``Y = Jf⁻ᵀ Jm_uᵀ`` (6 right-hand sides, from the solve's factorisation).

The helpers shared with :mod:`pincal.sensitivity.batch._batch_jacobian` (the measured
frame's free-dof Jacobian, the adjoint) live here.
"""

from __future__ import annotations

import numpy as np

from pincal.model import BatchKinematics, Linearisation, Mechanism, ParameterSet
from pincal.model.kernels import PassiveFactor, cross_cols
from pincal.sensitivity._jacobian import JacobianPlan
from pincal.sensitivity.batch._batch_serial import anchors

__all__ = ["point_path"]


def measured_free_jacobian(
    mech: Mechanism, bk: BatchKinematics, Rm: np.ndarray, pm: np.ndarray
) -> np.ndarray:
    """(N, 6, k) derivative of ``[p_world; rotation (local)]`` w.r.t. the free dofs."""
    free = mech.free_dofs
    sup = mech.batch_model.support_of_frame(mech.frame_id(mech.measured_frame))[free]
    Jv, Jw = bk.jacobian[:, :3, free], bk.jacobian[:, 3:, free]
    v = Jv + cross_cols(Jw, pm[:, :, None])
    return np.concatenate([v, np.swapaxes(Rm, 1, 2) @ Jw], axis=1) * sup


def point_factor(mech: Mechanism, bk: BatchKinematics) -> PassiveFactor:
    """The passive closure factorisation of ``bk``: the solve's, or computed here."""
    if bk.closure_factor is not None:
        return bk.closure_factor
    Jf = bk.closure_jacobian
    if Jf is None:
        Jf = mech.closure_terms_batch(bk, columns=mech.free_dofs)[1]
    return mech.passive_factor(Jf)


def adjoint(mech: Mechanism, bk: BatchKinematics, Jm_u: np.ndarray) -> np.ndarray:
    """``Y = (Jfᵀ)⁺ Jm_uᵀ`` (N, rows, 6) (``Jf⁻ᵀ Jm_uᵀ`` where Jf is square)."""
    return point_factor(mech, bk).solve_transposed(np.swapaxes(Jm_u, 1, 2))


def _cross_t(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross products ``a × b`` of vectors stored on axis −2 (arrays (…, 3, N), broadcast)."""
    a0, a1, a2 = a[..., 0, :], a[..., 1, :], a[..., 2, :]
    b0, b1, b2 = b[..., 0, :], b[..., 1, :], b[..., 2, :]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-2)


def _world_twists(
    mech: Mechanism,
    params: ParameterSet,
    bk: BatchKinematics,
    values: np.ndarray | Linearisation,
    plan: JacobianPlan,
) -> tuple[np.ndarray, np.ndarray]:
    """World twists ``V`` and ``W`` (n, 3, N) of every parameter column (see module doc).

    Origin j hangs at the constant placement ``(R0_j, p0_j)`` on body ``parent_j``, so
    ``R_o eff = R_parent (R0_j eff)``: the constant factors ``[R0 eff_v, R0 eff_ω, p0]``
    of a group of joints with the same number of parameters multiply the parents'
    rotations in one product per joint, for all poses. Poses are the last axis, so that
    per-column factors broadcast over long contiguous rows.
    """
    names, parents, R0, p0 = anchors(mech, plan)
    N, n = bk.q.shape[0], len(params)
    twists = params.linearise(values).joint_twists
    V, W = np.zeros((n, 3, N)), np.zeros((n, 3, N))
    groups: dict[int, list[int]] = {}
    for i, j in enumerate(names):
        groups.setdefault(twists[j][2].shape[1], []).append(i)
    for c, members in groups.items():
        G = len(members)
        eff = np.stack([twists[names[i]][2] for i in members])  # (G, 6, c)
        R = R0[members]
        E = np.concatenate([R @ eff[:, :3], R @ eff[:, 3:], p0[members, :, None]], axis=2)
        Rp = np.ascontiguousarray(np.swapaxes(bk.rotations[:, parents[members]], 0, 1))
        X = (Rp.reshape(G, N * 3, 3) @ E).reshape(G, N, 3, 2 * c + 1)
        X = np.ascontiguousarray(np.transpose(X, (0, 3, 2, 1)))  # (G, 2c + 1, 3, N)
        A, B = X[:, :c], X[:, c : 2 * c]  # R_o v, R_o ω: (G, c, 3, N)
        p = np.transpose(bk.translations[:, parents[members]], (1, 2, 0)) + X[:, -1]
        cols = np.concatenate([twists[names[i]][0] for i in members])
        V[cols] = (A + _cross_t(p[:, None], B)).reshape(G * c, 3, N)
        W[cols] = B.reshape(G * c, 3, N)
    return V, W


def _column_masks(
    mech: Mechanism, params: ParameterSet, plan: JacobianPlan, frame: str
) -> np.ndarray:
    """(n,) 1.0 on the columns of the parameterised joints below ``frame``."""
    below = set(plan.moves[frame])
    return np.array([float(p.joint in below) for p in params.parameters])


def _closure_columns(
    mech: Mechanism, params: ParameterSet, plan: JacobianPlan
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per point closure, the parameter columns that move its frames (padded to w).

    Returns:
        Columns (C, w) (a closure's list padded by repeating its first column, written
        twice with the same value), masks s_a and s_b (C, w) of the columns below frame
        a and b, and the flat index (3, C, w) of each entry in a (3C × n) array.
    """
    n = len(params)
    ma = np.array([_column_masks(mech, params, plan, c.frame_a) for c in mech.closures])
    mb = np.array([_column_masks(mech, params, plan, c.frame_b) for c in mech.closures])
    touched = [np.nonzero(a + b)[0] for a, b in zip(ma, mb, strict=True)]
    w = max(t.size for t in touched)
    cols = np.array(
        [np.pad(t, (0, w - t.size), mode="edge") if t.size else np.zeros(w, int) for t in touched]
    ).reshape(len(touched), w)
    sa, sb = np.take_along_axis(ma, cols, 1), np.take_along_axis(mb, cols, 1)
    rows = 3 * np.arange(len(touched))[None, :, None] + np.arange(3)[:, None, None]
    return cols, sa, sb, rows * n + cols[None]


def point_path(
    mech: Mechanism,
    params: ParameterSet,
    bk: BatchKinematics,
    values: np.ndarray | Linearisation,
    plan: JacobianPlan,
    out: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Measured rotation (N, 3, 3), position (N, 3) and Jacobian (N, 6, n), point closures.

    The Jacobian of ``[p_world; rotation (local)]`` is written into ``out`` when given.
    """
    N, n = bk.q.shape[0], len(params)
    V, W = _world_twists(mech, params, bk, values, plan)  # (n, 3, N)
    bm = mech.batch_model
    Rm, pm = bm.frame_placement(bk, mech.frame_id(mech.measured_frame))
    m = _column_masks(mech, params, plan, mech.measured_frame)[:, None, None]
    Rt = np.transpose(Rm, (1, 2, 0))  # (3, 3, N)
    J = np.empty((N, 6, n)) if out is None else out
    J[:, :3] = np.transpose((V + _cross_t(W, pm.T)) * m, (2, 1, 0))
    rot = Rt[0] * W[:, 0:1] + Rt[1] * W[:, 1:2] + Rt[2] * W[:, 2:3]  # Rmᵀ W
    J[:, 3:] = np.transpose(rot * m, (2, 1, 0))
    cols, sa, sb, flat = _closure_columns(mech, params, plan)
    fa = np.array([mech.frame_id(c.frame_a) for c in mech.closures])
    fb = np.array([mech.frame_id(c.frame_b) for c in mech.closures])
    pa = np.transpose(bm.frame_positions(bk, fa), (1, 2, 0))[:, None]  # (C, 1, 3, N)
    pb = np.transpose(bm.frame_positions(bk, fb), (1, 2, 0))[:, None]
    sa, sb = sa[..., None, None], sb[..., None, None]
    # ∂c/∂p on each closure's columns (C, w, 3, N), written into (N, 3C, n)
    rate = V[cols] * (sb - sa) + _cross_t(W[cols], pb * sb - pa * sa)
    dc = np.zeros((N, 3 * len(mech.closures), n))
    dc.reshape(N, -1)[:, flat] = np.transpose(rate, (3, 2, 0, 1))
    Y = adjoint(mech, bk, measured_free_jacobian(mech, bk, Rm, pm))
    J -= np.swapaxes(Y, 1, 2) @ dc
    return Rm, pm, J
