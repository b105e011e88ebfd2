"""Inverse kinematics of a mechanism: actuator values that reach a measured-frame pose.

A damped Newton over every tangent dof on the closure residual plus the measured
components of the pose error, kept only on home's assembly branch, with a diagnosis
of dead start points (where the actuators move the output in fewer directions).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from pincal.errors import ConvergenceError, ShapeError, UnreachablePoseError
from pincal.model.files import COMPONENTS, measured_jacobian
from pincal.model.loops._branch import LoopSolver
from pincal.model.loops._fixing import fixing_components
from pincal.model.loops._jacobian_shape import six_by_nv

__all__ = ["check_actuator_limits", "inverse_configuration"]


def check_actuator_limits(q_act: np.ndarray, limits: np.ndarray, actuated: tuple[str, ...]) -> None:
    """Check that actuator values (n_act,) lie within ``limits`` (n_act, 2) [m or rad].

    Raises:
        UnreachablePoseError: the first actuator outside its limits (``actuated`` names it).
    """
    lo, hi = limits.T
    bad = np.nonzero((q_act < lo - 1e-12) | (q_act > hi + 1e-12))[0]
    if bad.size:
        k = int(bad[0])
        raise UnreachablePoseError(
            f"target pose needs joint {actuated[k]!r} = {q_act[k]:.6g}, outside "
            f"its limits [{lo[k]:.6g}, {hi[k]:.6g}]"
        )


def inverse_configuration(
    loop: LoopSolver,
    measured_components: tuple[str, ...],
    T_world_target: pin.SE3,
    q_guess: np.ndarray | None = None,
) -> np.ndarray:
    """Full closed configuration (nq,) that brings the measured frame to the target.

    Only ``measured_components`` (names from x y z rx ry rz) are imposed.

    Args:
        loop: the pose-by-pose loop solver of the mechanism (its queries, home, branch).
        measured_components: the components imposed.
        T_world_target: the target placement of the measured frame (SE3 or (4, 4)) [m].
        q_guess: (nq,) start configuration (default home).

    Raises:
        UnreachablePoseError: no convergence, or the target is reached only on another
            assembly mode than home's.
    """
    queries = loop.queries
    T_world_target = _as_se3(T_world_target)
    fid = queries.frame_id(queries.measured_frame)
    comps = np.array([COMPONENTS.index(c) for c in measured_components])
    target_p, target_R = T_world_target.translation, T_world_target.rotation
    model = queries.model

    def extra(data: pin.Data) -> tuple[np.ndarray, np.ndarray]:
        oMf = data.oMf[fid]
        r = np.zeros(6)
        r[:3] = oMf.translation - target_p
        E = target_R.T @ oMf.rotation
        r[3:] = pin.log3(E)
        J = measured_jacobian(oMf, six_by_nv(pin.getFrameJacobian(model, data, fid, pin.LOCAL)))
        J[3:] = pin.Jlog3(E) @ J[3:]
        return r[comps], J[comps]

    guess = loop.q_home if q_guess is None else queries.check_q(q_guess)
    # from home the verdict is the mechanism's: checked once per set of components
    note = loop.home_notes.get(measured_components) if q_guess is None else None
    if note is None:
        note = _check_independent(loop, measured_components, guess, fid, target_p)
        if q_guess is None:
            loop.home_notes[measured_components] = note
    try:
        sol = loop.newton(guess, np.arange(model.nv), extra)
    except ConvergenceError as exc:
        raise UnreachablePoseError(
            f"target pose unreachable (p = {np.round(target_p * 1e3, 3).tolist()} mm): "
            f"residual {exc.residual * 1e3:.3g} mm/mrad after Newton" + note,
            residual=exc.residual,
        ) from exc
    if loop.idle_branch and loop.branch_sign(sol.q) != loop.idle_branch:
        raise UnreachablePoseError(
            f"target pose (p = {np.round(target_p * 1e3, 3).tolist()} mm) is reached only in "
            f"another assembly mode than home's: forward kinematics would not return it; "
            f"give q_guess on home's mode or choose another target",
            residual=0.0,
        )
    return into_limits(model, sol.q)


def into_limits(model: pin.Model, q: np.ndarray) -> np.ndarray:
    """``q`` (nq,) with each revolute joint outside its limits turned by whole turns into them.

    Newton integrates a revolute joint's angle freely, so it may end a full turn away from
    the range (−0.52 rad for a joint limited to [0.33, 5.95] that reaches the same pose at
    5.76 rad); the configuration that many turns away is the same pose. A joint no whole
    turn brings inside is left as it is (the actuator limit check names it). Continuous
    joints (cos, sin) and joints without a range are untouched.
    """
    out = np.array(q, dtype=float)
    lo, hi = model.lowerPositionLimit, model.upperPositionLimit
    for j in range(1, model.njoints):
        joint = model.joints[j]
        if joint.nq != 1 or not joint.shortname().startswith(("JointModelR", "JointModelRevolute")):
            continue
        i = joint.idx_q
        if not (np.isfinite(lo[i]) and np.isfinite(hi[i])) or lo[i] <= out[i] <= hi[i]:
            continue
        turns = (
            np.ceil((lo[i] - out[i]) / (2 * np.pi))
            if out[i] < lo[i]
            else -np.ceil((out[i] - hi[i]) / (2 * np.pi))
        )
        if lo[i] <= out[i] + 2 * np.pi * turns <= hi[i]:
            out[i] += 2 * np.pi * turns
    return out


def _output_map(loop: LoopSolver, q: np.ndarray, fid: int) -> tuple[np.ndarray, float]:
    """The actuator → six-components map G (6, n_act) at q, the loops staying closed.

    Returns G and the largest entry of the measured frame's Jacobian (the rank's scale).
    """
    data = loop.queries.compute(q)
    J_frame = six_by_nv(pin.getFrameJacobian(loop.model, data, fid, pin.LOCAL))
    Jm = measured_jacobian(data.oMf[fid], J_frame)
    Jc = loop.queries.jacobian_of(data)
    act, free = loop.queries.act_v_arr, loop.queries.free_v
    dq_free = -np.linalg.pinv(Jc[:, free], rcond=loop.options.rcond) @ Jc[:, act]
    G = Jm[:, act] + Jm[:, free] @ dq_free
    return G, max(float(np.max(np.abs(Jm), initial=0.0)), 1e-300)


def _rank(G: np.ndarray, scale: float) -> int:
    """Rank of an actuator map (k, n_act) relative to ``scale`` (1e-9)."""
    return int(np.sum(np.linalg.svd(G, compute_uv=False) > 1e-9 * scale))


def _output_rank(loop: LoopSolver, q: np.ndarray, fid: int, comps: np.ndarray) -> int:
    """Rank of the actuator → measured-components map at q, the loops staying closed."""
    G, scale = _output_map(loop, q, fid)
    return _rank(G[comps], scale)


def _nearby_rank(loop: LoopSolver, q: np.ndarray, fid: int, comps: np.ndarray) -> int:
    """The largest :func:`_output_rank` at 3 seeded configurations within 1e-3 [m, rad] of q."""
    rng = np.random.default_rng(0)
    steps = (1e-3 * rng.standard_normal(loop.model.nv) for _ in range(3))
    return max(_output_rank(loop, pin.integrate(loop.model, q, dq), fid, comps) for dq in steps)


def _check_independent(
    loop: LoopSolver,
    measured_components: tuple[str, ...],
    q: np.ndarray,
    fid: int,
    target_p: np.ndarray,
) -> str:
    """Refuse imposed components that are locally dependent at q and nearby.

    Their actuator map (k, n_act) must have rank min(k, n_act): k components the
    actuators move independently, which fix the commands when k ≥ n_act. Short of it at
    q only, q is a dead point (:func:`_dead_start_note`); short of it at 3 random
    configurations within 1e-3 [m, rad] too, no start helps: Newton would return one
    of a family of commands (a planar five-bar imposing x z moves z by neither motor).

    Returns:
        what to say if Newton stalls: "" or, at a dead point, :func:`_dead_start_note`.

    Raises:
        UnreachablePoseError: the imposed components are dependent here and nearby.
    """
    comps = np.array([COMPONENTS.index(c) for c in measured_components])
    n = len(loop.queries.actuated)
    need = min(len(comps), n)
    G, scale = _output_map(loop, q, fid)
    rank = _rank(G[comps], scale)
    if rank >= need:
        return ""
    nearby = _nearby_rank(loop, q, fid, comps)
    if nearby >= need:
        return _dead_start_note(loop, measured_components, rank, nearby)
    G[np.abs(G) <= 1e-9 * float(np.abs(G).max(initial=0.0))] = 0.0
    _, fixing = fixing_components(G, measured_components)
    raise UnreachablePoseError(
        f"target pose (p = {np.round(target_p * 1e3, 3).tolist()} mm): the imposed components "
        f"[{', '.join(measured_components)}] are locally dependent: the actuators "
        f"{list(loop.queries.actuated)} move them in only {nearby} independent "
        f"direction(s) here and nearby, so they do not fix the commands (inverse kinematics "
        f"would return one of many); impose "
        + (f"[{', '.join(fixing)}]" if fixing else f"{need} components the actuators move")
        + " instead (sidecar 'measured', or the components asked of compensate)",
        residual=float("nan"),
    )


def _dead_start_note(
    loop: LoopSolver, measured_components: tuple[str, ...], rank: int, nearby: int
) -> str:
    """Why inverse kinematics may not leave a dead point of the start configuration.

    A dead point: the actuators move the measured components in fewer directions there
    (``rank``) than at nearby configurations (``nearby``; first order, loops closed).
    """
    return (
        f". At the start configuration the actuators {list(loop.queries.actuated)} move the "
        f"measured components {list(measured_components)} in only {rank} "
        f"independent direction(s) at first order, {nearby} nearby (a dead point of the "
        f"output): Newton cannot leave it, and nearby targets are reached by several "
        f"actuator values (e.g. a mirror-symmetric machine). Give q_guess near the "
        f"solution, or put the sidecar 'home' away from the dead point and keep the "
        f"workspace on one side of it"
    )


def _as_se3(T: object) -> pin.SE3:
    """A pin.SE3, or a (4, 4) homogeneous matrix turned into one."""
    if isinstance(T, pin.SE3):
        return T
    try:
        M = np.asarray(T, dtype=float)
    except (TypeError, ValueError):
        M = np.zeros(0)
    if M.shape != (4, 4) or not np.all(np.isfinite(M)):
        raise ShapeError(
            f"target pose must be a pinocchio.SE3 or a finite (4, 4) matrix, got {type(T).__name__}"
            f"{' of shape ' + str(M.shape) if M.size else ''}"
        )
    R = M[:3, :3]
    if not np.allclose(R.T @ R, np.eye(3), atol=1e-9) or np.linalg.det(R) < 0:
        raise ShapeError("target pose matrix: the upper-left (3, 3) block must be a rotation")
    return pin.SE3(R, M[:3, 3])
