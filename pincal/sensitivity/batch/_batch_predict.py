"""First-order prediction of closed configurations after a parameter change.

When an identification step changes the parameters by δ, each pose's passive joints
move by ``dq_u = −(∂c/∂q_u)⁻¹ ∂c/∂p · δ`` to first order (the implicit-function step of
the loop closures c). Started from that prediction, the loop-closing Newton of the next
evaluation meets its tolerance in one iteration where it needed about three from the
old solution; the prediction is only a start guess (the solve still closes the loops
to its tolerance and checks the assembly branch).
"""

from __future__ import annotations

import numpy as np

from pincal.model import BatchKinematics, Linearisation, Mechanism, ParameterSet
from pincal.model.kernels import closure_jacobian_batch, cross3, mv
from pincal.sensitivity._jacobian import JacobianPlan, jacobian_plan
from pincal.sensitivity.batch._batch_jacobian import batch_applies, param_twists
from pincal.sensitivity.batch._batch_serial import anchors

__all__ = ["predict_configurations"]


def predict_configurations(
    mech: Mechanism,
    params: ParameterSet,
    bk: BatchKinematics,
    values: np.ndarray | Linearisation,
    delta: np.ndarray,
) -> np.ndarray | None:
    """First-order prediction of closed configurations after a parameter change.

    The implicit-function step of the passive joints, ``dq_u = −(∂c/∂q_u)⁻¹ ∂c/∂p · δ``,
    from the closed configurations ``bk`` of ``mech`` (at parameter ``values``): a start
    guess whose closure residual is O(‖δ‖²), so the loop-closing Newton needs one
    iteration where it needed three from ``bk.q``. The prediction is only a guess: the
    solve that follows still closes the loops to its tolerance and checks the branch.

    Args:
        mech: the mechanism at parameter ``values`` (the one ``bk`` was solved on).
        params: the n parameters.
        bk: (N poses) kinematics of its closed configurations, with ``closure_jacobian``.
        values: (n,) parameter values of ``mech`` [SI], or their :class:`Linearisation`.
        delta: (n,) parameter change [SI].

    Returns:
        (N, nq) predicted configurations (rows whose step is not finite, exceeds the
        solver's ``max_step`` or is below its ``tol`` keep ``bk.q``), or None when the
        prediction does not apply (no closures, closures not batch-solvable, batched
        kinematics unsupported).
    """
    Jf = bk.closure_jacobian
    if not mech.closures or Jf is None or not batch_applies(mech):
        return None
    plan = jacobian_plan(mech, params)
    values = params.linearise(values)
    delta = np.asarray(delta, dtype=float)
    if all(c.is_point for c in mech.closures):
        Jc = _point_closure_rates(mech, params, bk, values, plan, delta)
    else:
        place, P = param_twists(mech, params, bk, values, plan, delta)
        Jc = np.concatenate(
            [
                closure_jacobian_batch(
                    c, *place[c.frame_a], *place[c.frame_b], P[c.frame_a], P[c.frame_b]
                )
                for c in mech.closures
            ],
            axis=1,
        )[..., 0]
    factor = bk.closure_factor if bk.closure_factor is not None else mech.passive_factor(Jf)
    try:
        step = -factor.solve(Jc[..., None])[..., 0]
    except np.linalg.LinAlgError:
        return None
    # rows keep bk.q when the step is not finite, too long, or below the solver's
    # tolerance (a change the solve would not see: the old solution is reused exactly)
    size = np.linalg.norm(step, axis=1)
    keep = ~np.isfinite(size) | (size > mech.options.max_step) | (size <= mech.options.tol)
    step[keep] = 0.0
    DV = np.zeros((step.shape[0], mech.model.nv))
    DV[:, mech.free_dofs] = step
    return mech.batch_model.integrate(bk.q, DV)


def _point_closure_rates(
    mech: Mechanism,
    params: ParameterSet,
    bk: BatchKinematics,
    values: np.ndarray | Linearisation,
    plan: JacobianPlan,
    delta: np.ndarray,
) -> np.ndarray:
    """(N, n_closure_rows) derivative of point-closure residuals along ``delta`` at fixed q.

    Origin j displaced by the local twist ``[v; ω] = eff_j · δ_j`` moves a world point x
    by ``V_j + W_j × (x − o_j)`` (V, W: v, ω in world axes; o_j: origin position); a
    residual ``p_b − p_a`` by the sum over the joints that move b minus those that move a.
    """
    names, parents, R0, p0 = anchors(mech, plan)
    twists = params.linearise(values).joint_twists
    T = np.array([twists[j][2] @ delta[twists[j][0]] for j in names])  # (J, 6)
    Rp = bk.rotations[:, parents]
    po = bk.translations[:, parents] + mv(Rp, p0)
    V, W = mv(Rp, mv(R0, T[:, :3])), mv(Rp, mv(R0, T[:, 3:]))  # (N, J, 3) world axes
    U = V - cross3(W, po)
    Sa = np.array([[float(j in plan.moves[c.frame_a]) for j in names] for c in mech.closures])
    Sb = np.array([[float(j in plan.moves[c.frame_b]) for j in names] for c in mech.closures])
    fids = [mech.frame_id(f) for c in mech.closures for f in (c.frame_a, c.frame_b)]
    p = mech.batch_model.frame_positions(bk, np.array(fids))
    rate = (Sb - Sa) @ U + cross3(Sb @ W, p[:, 1::2]) - cross3(Sa @ W, p[:, 0::2])  # (N, C, 3)
    return rate.reshape(rate.shape[0], -1)
