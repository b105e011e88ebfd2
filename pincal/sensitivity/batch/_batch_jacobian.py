"""The identification Jacobian of N closed configurations at once (arrays (N, …)).

The same mathematics as :func:`pincal.sensitivity.pose_sensitivity` (see
:mod:`pincal.sensitivity._jacobian`), evaluated on the batched kinematics of
:mod:`pincal.model.batch._batch`: the local twist of a key frame per unit of each parameter
is a batched adjoint ``Ad(oMf⁻¹ · A_j) · eff_j``; the passive motion
``dq_u/dp = −(∂c/∂q_u)⁺ ∂c/∂p`` enters through one adjoint solve with the forward
kinematics' factorisation of ``∂c/∂q_u`` (block LU where square; thin QR where
closure rows are redundant or passive motion is idle, the minimum-norm least-squares
solution of the pose-by-pose truncated SVD). With redundant rows, a parameter whose
closure column leaves the range of ``∂c/∂q_u`` is reported as breaking closure, by the
rule of :func:`pose_sensitivity`.

It applies to serial chains and wherever the forward kinematics closes the loops in
batch (:attr:`Mechanism.batch_solvable`); elsewhere (a joint type the batched
kinematics lacks, a passive closure Jacobian of rank below min(rows, dofs) at home)
:func:`sensitivities_batch` falls back to :func:`pose_sensitivity` pose by pose.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from pincal.model import BatchKinematics, Linearisation, Mechanism, ParameterSet
from pincal.model.kernels import (
    CHUNK,
    RangeFactor,
    closure_jacobian_batch,
    cross3,
    cross_cols,
    mm,
    mv,
    slice_kinematics,
)
from pincal.sensitivity._jacobian import (
    BatchSensitivity,
    JacobianPlan,
    jacobian_plan,
    pose_sensitivity,
)
from pincal.sensitivity._joint_terms import joint_term_sensitivities
from pincal.sensitivity._rank import RANK_RTOL
from pincal.sensitivity.batch._batch_points import (
    adjoint,
    measured_free_jacobian,
    point_factor,
    point_path,
)
from pincal.sensitivity.batch._batch_serial import anchors, serial_columns, serial_path

__all__ = ["BatchSensitivity", "batch_applies", "sensitivities_batch"]


def batch_applies(mech: Mechanism) -> bool:
    """Whether the batched Jacobian applies: serial chains, or batch-solvable closures."""
    return mech.batch_model.supported and (not mech.closures or mech.batch_solvable)


def param_twists(
    mech: Mechanism,
    params: ParameterSet,
    bk: BatchKinematics,
    values: np.ndarray | Linearisation,
    plan: JacobianPlan,
    direction: np.ndarray | None = None,
) -> tuple[dict[str, tuple[np.ndarray, np.ndarray]], dict[str, np.ndarray]]:
    """Placements of the plan's frames and their (N, 6, n) local parameter twists.

    With a ``direction`` (n,) in parameter space, the twists (N, 6, 1) per unit step
    along it instead.
    """
    bm, model = mech.batch_model, mech.model
    N, n = bk.q.shape[0], len(params)
    twists = params.linearise(values).joint_twists
    if direction is not None:
        zero = np.zeros(1, dtype=int)
        twists = {j: (zero, v, (eff @ direction[c])[:, None]) for j, (c, v, eff) in twists.items()}
        n = 1
    placements = {f: bm.frame_placement(bk, mech.frame_id(f)) for f in plan.frames}
    origins = {}
    for j, (fid, jid, parent) in plan.origins.items():
        if fid >= 0:
            origins[j] = placements[j]
        else:
            M = model.jointPlacements[jid]
            Rp, pp = bk.rotations[:, parent], bk.translations[:, parent]
            origins[j] = (mm(Rp, M.rotation), pp + mv(Rp, M.translation))
    out = {}
    for frame in mech.key_frames:
        P = np.zeros((N, 6, n))
        Rf, pf = placements[frame]
        Rft = np.swapaxes(Rf, 1, 2)
        for j in plan.moves[frame]:
            cols, _, eff = twists[j]
            Ro, po = origins[j]
            Rx = mm(Rft, Ro)  # oMf⁻¹ · A_j
            px = mv(Rft, po - pf)
            ang = mm(Rx, eff[3:])
            P[:, 3:, cols] += ang  # columns distinct per joint, or one direction
            P[:, :3, cols] += mm(Rx, eff[:3]) + cross_cols(px[:, :, None], ang)
        out[frame] = P
    return placements, out


def _origins(
    mech: Mechanism, bk: BatchKinematics, plan: JacobianPlan
) -> tuple[list[str], np.ndarray, np.ndarray]:
    """Parameterised joints and their origins' world placements.

    Returns:
        The J joint names, rotations (N, J, 3, 3) and positions (N, J, 3) [m].
    """
    names, parents, R0, p0 = anchors(mech, plan)
    Rp = bk.rotations[:, parents]
    return names, Rp @ R0, bk.translations[:, parents] + mv(Rp, p0)


def _cross_rows(d: np.ndarray, R: np.ndarray) -> np.ndarray:
    """``skew(d) @ R`` of stacked vectors d (…, 3) and matrices R (…, 3, 3)."""
    r0, r1, r2 = R[..., 0, :], R[..., 1, :], R[..., 2, :]
    d0, d1, d2 = d[..., 0:1], d[..., 1:2], d[..., 2:3]
    return np.stack([d1 * r2 - d2 * r1, d2 * r0 - d0 * r2, d0 * r1 - d1 * r0], axis=-2)


def _closure_maps(
    mech: Mechanism,
    plan: JacobianPlan,
    names: list[str],
    Ro: np.ndarray,
    po: np.ndarray,
    place: dict[str, tuple[np.ndarray, np.ndarray]],
    Y: np.ndarray,
    C: np.ndarray,
) -> None:
    """Add ``−Yᵀ ∂c/∂(origin twist)`` of every closure into the joint maps C (N, J, 6, 6).

    A local twist of origin j moves a world point x by ``Ro v + (po − x) × Ro ω``; a point
    closure's residual ``p_b − p_a`` by ``[σ Ro, skew(d) Ro]`` with σ = [j moves b] −
    [j moves a] and d = [j moves b](po − p_b) − [j moves a](po − p_a). All (point
    closure, joint) pairs are stacked into one set of array operations.
    """
    pairs, row = [], 0
    for c in mech.closures:
        ma, mb = set(plan.moves[c.frame_a]), set(plan.moves[c.frame_b])
        for i, j in enumerate(names):
            if j in ma or j in mb:
                pairs.append((c, row, i, float(j in ma), float(j in mb)))
        row += c.size
    point = [t for t in pairs if t[0].is_point]
    if point:
        jP = np.array([t[2] for t in point])
        sa, sb = np.array([t[3] for t in point]), np.array([t[4] for t in point])
        pa = np.stack([place[t[0].frame_a][1] for t in point], axis=1)
        pb = np.stack([place[t[0].frame_b][1] for t in point], axis=1)
        RoP, poP = Ro[:, jP], po[:, jP]
        d = sb[:, None] * (poP - pb) - sa[:, None] * (poP - pa)
        rows = np.array([t[1] for t in point])[:, None] + np.arange(3)
        Yt = np.swapaxes(Y[:, rows], -1, -2)  # (N, P, 6, 3)
        # −Yᵀ[σ Ro, skew(d) Ro] = −[σ Yᵀ Ro, (Yᵀ skew(d)) Ro], rows of Yᵀ skew(d) = y × d
        contrib = np.empty((*Yt.shape[:2], 6, 6))
        contrib[..., :3] = (sa - sb)[:, None, None] * (Yt @ RoP)
        contrib[..., 3:] = cross3(d[:, :, None], Yt) @ RoP
        if np.unique(jP).size == jP.size:
            C[:, jP] += contrib
        else:  # a joint moving several closures (a base joint, say)
            for k, i in enumerate(jP):
                C[:, i] += contrib[:, k]
    for c, r0, i, sa_, sb_ in pairs:
        if c.is_point or sa_ == sb_:
            continue  # moving both frames of a positional closure expressed in a: no change
        Ra, pb = place[c.frame_a][0], place[c.frame_b][1]
        pmap = np.concatenate([Ro[:, i], _cross_rows(po[:, i] - pb, Ro[:, i])], axis=-1)
        blk = (np.swapaxes(Ra, 1, 2) @ pmap)[:, list(c.components)] * (sb_ - sa_)
        C[:, i] -= np.swapaxes(Y[:, r0 : r0 + c.size], 1, 2) @ blk


def _world_path(
    mech: Mechanism,
    params: ParameterSet,
    bk: BatchKinematics,
    values: np.ndarray | Linearisation,
    plan: JacobianPlan,
    out: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Measured rotation, position and Jacobian (N, 6, n) when every closure is positional.

    The Jacobian is written into ``out`` (N, 6, n) when given. Per parameterised joint
    j, the Jacobian columns are ``C_j · eff_j``: C_j (N, 6, 6) maps a local twist of j's
    origin to the measured quantity (directly, and through the passive joints that
    re-close the loops), eff_j (6, c) is the joint's constant twists per parameter
    (one GEMM). The passive part ``Jm_u · dq_u/dp =
    −(Jm_u Jf⁻¹) ∂c/∂p`` uses one adjoint solve ``Y = Jf⁻ᵀ Jm_uᵀ`` (6 right-hand sides,
    not n).
    """
    if not mech.closures:
        return serial_path(mech, params, bk, values, plan, out)
    if all(c.is_point for c in mech.closures):
        return point_path(mech, params, bk, values, plan, out)
    N, n = bk.q.shape[0], len(params)
    names, Ro, po = _origins(mech, bk, plan)
    key = [mech.measured_frame, *(f for c in mech.closures for f in (c.frame_a, c.frame_b))]
    frames = list(dict.fromkeys(key))
    Rs, ps = mech.batch_model.frame_placements(bk, np.array([mech.frame_id(f) for f in frames]))
    place = {f: (Rs[:, i], ps[:, i]) for i, f in enumerate(frames)}
    Rm, pm = place[mech.measured_frame]
    C: np.ndarray | None = None  # closure part of the joint maps
    moves = set(plan.moves[mech.measured_frame])
    mj = [i for i, j in enumerate(names) if j in moves]
    touched = {i: k for k, i in enumerate(mj)}  # joint index → its measured map
    Cm = np.zeros((N, len(mj), 6, 6))
    if mj:
        R = Ro[:, mj]
        Cm[:, :, :3, :3] = R
        Cm[:, :, :3, 3:] = _cross_rows(po[:, mj] - pm[:, None], R)
        Cm[:, :, 3:, 3:] = np.swapaxes(Rm, 1, 2)[:, None] @ R
    if mech.closures:
        Y = adjoint(mech, bk, measured_free_jacobian(mech, bk, Rm, pm))
        C = np.zeros((N, len(names), 6, 6))
        _closure_maps(mech, plan, names, Ro, po, place, Y, C)
    twists = params.linearise(values).joint_twists
    J = np.zeros((N, 6, n)) if out is None else out
    for i, j in enumerate(names):
        if C is not None and i in touched:
            Ci = C[:, i] + Cm[:, touched[i]]
        elif C is not None:
            Ci = np.ascontiguousarray(C[:, i])
        elif i in touched:
            Ci = np.ascontiguousarray(Cm[:, touched[i]])
        else:
            continue
        cols, _, eff = twists[j]
        J[:, :, serial_columns(cols)] = (Ci.reshape(-1, 6) @ eff).reshape(N, 6, -1)
    return Rm, pm, J


def sensitivities_batch(
    mech: Mechanism,
    params: ParameterSet,
    qs: np.ndarray,
    bk: BatchKinematics | None = None,
    values: np.ndarray | Linearisation | None = None,
    basis: np.ndarray | None = None,
    conditions: Mapping[str, np.ndarray | None] | None = None,
) -> BatchSensitivity:
    """Sensitivity of the measured frame at N closed configurations.

    Args:
        mech: the mechanism at parameter ``values`` (as for :func:`pose_sensitivity`).
        params: the n parameters.
        qs: (N, nq) closed configurations.
        bk: their batched kinematics when already computed (e.g. by
            ``mech.configurations_batch``); computed when None.
        values: (n,) parameter values (default zeros), or their :class:`Linearisation`.
        basis: (N, n_act, n) joint-term basis at the commanded joint values (see
            :mod:`pincal.sensitivity._joint_terms`); None: at the actuated values of qs.
        conditions: per-pose conditions joint terms need (e.g. the temperature), used
            when ``basis`` is None; the columns of terms moving the measured frame
            (:func:`pincal.model.joint_term_shift`) then include that move.

    Returns:
        The :class:`BatchSensitivity` (equal to :func:`pose_sensitivity` pose by pose).
    """
    lin = params.linearise(values)
    if params.joint_terms.size:
        return joint_term_sensitivities(
            sensitivities_batch, mech, params, qs, bk, lin.values, basis, conditions
        )
    qs = np.atleast_2d(np.asarray(qs, dtype=float))
    n = len(params)
    plan = jacobian_plan(mech, params)
    if not batch_applies(mech):
        sens = [pose_sensitivity(mech, params, q, lin, plan) for q in qs]
        breaks = np.zeros(n, dtype=bool)
        for s in sens:
            breaks |= s.breaks_closure
        return BatchSensitivity(
            qs.copy(),
            np.array([s.position for s in sens]).reshape(-1, 3),
            np.array([s.rotation for s in sens]).reshape(-1, 3, 3),
            np.array([s.jacobian for s in sens]).reshape(-1, 6, n),
            breaks,
        )
    bk = bk if bk is not None else mech.kinematics_batch(qs)
    N = bk.q.shape[0]
    if not mech.closures:  # a serial chain: one call, blocked inside for the cache
        Rm, pm, J = serial_path(mech, params, bk, lin, plan, None)
        return BatchSensitivity(bk.q.copy(), pm, Rm, J, np.zeros(n, dtype=bool))
    redundant = mech.n_closure_rows > mech.closure_rank  # rows some parameters can break
    if redundant or any(c.components[-1] >= 3 for c in mech.closures):
        parts = [
            _local_path(mech, params, slice_kinematics(bk, slice(k, k + CHUNK)), lin, plan)
            for k in range(0, N, CHUNK)
        ]
        Rm, pm, J = (np.concatenate([p[i] for p in parts]) for i in range(3))
        breaks = np.any([p[3] for p in parts], axis=0)
        return BatchSensitivity(bk.q.copy(), pm, Rm, J, breaks)
    Rm, pm, J = np.empty((N, 3, 3)), np.empty((N, 3)), np.zeros((N, 6, n))
    for start in range(0, N, CHUNK):
        rows = slice(start, start + CHUNK)
        Rm[rows], pm[rows], _ = _world_path(
            mech, params, slice_kinematics(bk, rows), lin, plan, J[rows]
        )
    return BatchSensitivity(bk.q.copy(), pm, Rm, J, np.zeros(n, dtype=bool))


def _local_path(
    mech: Mechanism,
    params: ParameterSet,
    bk: BatchKinematics,
    values: np.ndarray | Linearisation,
    plan: JacobianPlan,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Measured rotation, position, Jacobian (N, 6, n) and closure breaking (n,).

    The general path (closures with orientation components, redundant closure rows):
    closure Jacobians from the frames' local twists, passive correction by one adjoint
    solve. A parameter breaks closure when its closure column has a part outside the
    range of the passive closure Jacobian (the rule of :func:`pose_sensitivity`).
    """
    placements, P = param_twists(mech, params, bk, values, plan)
    Rm, pm = placements[mech.measured_frame]
    Pm = P[mech.measured_frame]
    J = np.concatenate([mm(Rm, Pm[:, :3]), Pm[:, 3:]], axis=1)
    Jc_p = np.concatenate(
        [
            closure_jacobian_batch(
                c, *placements[c.frame_a], *placements[c.frame_b], P[c.frame_a], P[c.frame_b]
            )
            for c in mech.closures
        ],
        axis=1,
    )
    factor = point_factor(mech, bk)
    # Jm_u · dq_u/dp = −((Jfᵀ)⁺ Jm_uᵀ)ᵀ Jc_p: one solve with 6 right-hand sides
    Y = factor.solve_transposed(np.swapaxes(measured_free_jacobian(mech, bk, Rm, pm), 1, 2))
    breaks = np.zeros(len(params), dtype=bool)
    if isinstance(factor, RangeFactor):
        out = factor.out_of_range(Jc_p)  # (N, n)
        norms = np.sqrt(np.sum(Jc_p * Jc_p, axis=1))
        floor = 1e-12 * np.max(norms, axis=1, keepdims=True, initial=0.0)
        breaks = np.any((out > RANK_RTOL * norms) & (out > floor), axis=0)
    return Rm, pm, J - np.swapaxes(Y, 1, 2) @ Jc_p, breaks
