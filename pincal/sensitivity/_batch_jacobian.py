"""The identification Jacobian of N closed configurations at once (arrays (N, …)).

The same mathematics as :func:`pincal.sensitivity.pose_sensitivity` (see
:mod:`pincal.sensitivity._jacobian`), evaluated on the batched kinematics of
:mod:`pincal.model._batch`: the local twist of a key frame per unit of each parameter
is a batched adjoint ``Ad(oMf⁻¹ · A_j) · eff_j``; the passive motion
``dq_u/dp = −(∂c/∂q_u)⁻¹ ∂c/∂p`` is one ``np.linalg.solve`` over (N, k, k).

It applies where the passive closure Jacobian is square and regular on the forward
kinematics' branch (every bundled closed-loop model) and to serial chains; elsewhere
(over-constrained loops, where the truncated SVD and closure breaking matter)
:func:`sensitivities_batch` falls back to :func:`pose_sensitivity` pose by pose.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pincal.model._batch import BatchKinematics, cross_cols, mm, mv
from pincal.model._batch_fk import closure_jacobian_batch
from pincal.model._mechanism import Mechanism
from pincal.model._parameters import ParameterSet
from pincal.sensitivity._jacobian import _Plan, _plan, pose_sensitivity

__all__ = ["BatchSensitivity", "batch_applies", "sensitivities_batch"]


@dataclass(frozen=True)
class BatchSensitivity:
    """Sensitivities of N closed configurations.

    Attributes:
        q: (N, nq) configurations.
        positions: (N, 3) world positions of the measured frame [m].
        rotations: (N, 3, 3) its orientations.
        jacobian: (N, 6, n) derivative of ``[p_world; rotation (local)]`` w.r.t. the
            n parameters.
        breaks_closure: (n,) True for parameters that break a loop closure at some pose.
    """

    q: np.ndarray
    positions: np.ndarray
    rotations: np.ndarray
    jacobian: np.ndarray
    breaks_closure: np.ndarray


def batch_applies(mech: Mechanism) -> bool:
    """Whether the batched Jacobian applies: serial, or square regular passive closures."""
    return mech.batch_model.supported and (not mech.closures or mech.home_branch != 0.0)


def _param_twists(
    mech: Mechanism,
    params: ParameterSet,
    bk: BatchKinematics,
    values: np.ndarray,
    plan: _Plan,
) -> tuple[dict[str, tuple[np.ndarray, np.ndarray]], dict[str, np.ndarray]]:
    """Placements of the plan's frames and their (N, 6, n) local parameter twists."""
    bm, model = mech.batch_model, mech.model
    N, n = bk.q.shape[0], len(params)
    twists = params.joint_twists(values)
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
            P[:, 3:, cols] = ang
            P[:, :3, cols] = mm(Rx, eff[:3]) + cross_cols(px[:, :, None], ang)
        out[frame] = P
    return placements, out


def sensitivities_batch(
    mech: Mechanism,
    params: ParameterSet,
    qs: np.ndarray,
    bk: BatchKinematics | None = None,
    values: np.ndarray | None = None,
) -> BatchSensitivity:
    """Sensitivity of the measured frame at N closed configurations.

    Args:
        mech: the mechanism at parameter ``values`` (as for :func:`pose_sensitivity`).
        params: the n parameters.
        qs: (N, nq) closed configurations.
        bk: their batched kinematics when already computed (e.g. by
            ``mech.configurations_batch``); computed when None.
        values: (n,) parameter values (default zeros).

    Returns:
        The :class:`BatchSensitivity` (equal to :func:`pose_sensitivity` pose by pose).
    """
    values = params.check_values(values)
    qs = np.atleast_2d(np.asarray(qs, dtype=float))
    n = len(params)
    plan = _plan(mech, params)
    if not batch_applies(mech):
        sens = [pose_sensitivity(mech, params, q, values, plan) for q in qs]
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
    placements, P = _param_twists(mech, params, bk, values, plan)
    Rm, pm = placements[mech.measured_frame]
    Pm = P[mech.measured_frame]
    J = np.concatenate([mm(Rm, Pm[:, :3]), Pm[:, 3:]], axis=1)
    if mech.closures:
        free = mech.free_dofs
        Jc_p = np.concatenate(
            [
                closure_jacobian_batch(
                    c, *placements[c.frame_a], *placements[c.frame_b], P[c.frame_a], P[c.frame_b]
                )
                for c in mech.closures
            ],
            axis=1,
        )
        _, Jc = mech.closure_terms_batch(bk)
        dqu_dp = np.linalg.solve(Jc[:, :, free], -Jc_p)
        Jl = mech.batch_model.frame_jacobian(bk, mech.frame_id(mech.measured_frame))
        Jm_u = np.concatenate([mm(Rm, Jl[:, :3, free]), Jl[:, 3:, free]], axis=1)
        J = J + Jm_u @ dqu_dp
    return BatchSensitivity(bk.q.copy(), pm, Rm, J, np.zeros(n, dtype=bool))
