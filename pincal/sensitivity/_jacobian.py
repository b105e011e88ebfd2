"""Analytic identification Jacobian of closed-loop and serial mechanisms.

For a frame f downstream of the origin of URDF joint j, a displacement δ_k of the
origin along twist ξ_k moves f by the local twist ``Ad(oMf⁻¹ · A_j) ξ_k`` where
``A_j`` is the world placement of the (displaced) origin frame. Closures add the
passive-joint motion from the implicit-function theorem,
``dq_u/dp = −(∂c/∂q_u)⁺ ∂c/∂p`` (one truncated SVD of ∂c/∂q_u per pose, applied to
all parameter columns at once, rank-revealing with the mechanism's ``options.rcond``,
so redundant closure rows of over-constrained machines are harmless), and the
measured quantity's sensitivity is ``∂m/∂p + ∂m/∂q_u · dq_u/dp``. No finite
differences.

Over-constrained loops (a ``6d`` closure of a planar loop) have closure rows that no
passive motion can change. A parameter whose closure column ∂c/∂p_k has a part
outside the range of ∂c/∂q_u cannot change without opening a loop: it *breaks loop
closure* (:attr:`PoseSensitivity.breaks_closure`, :func:`closure_breaking`). For such
a parameter the least-squares column is not a derivative of anything measurable; for
every other parameter the Jacobian is exact.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from pincal.errors import ParameterError
from pincal.model import Kinematics, Linearisation, Mechanism, ParameterSet
from pincal.model.kernels import measured_jacobian
from pincal.sensitivity._rank import RANK_RTOL, RangeSolver

__all__ = ["BatchSensitivity", "PoseSensitivity", "pose_sensitivity"]


@dataclass(frozen=True)
class PoseSensitivity:
    """Sensitivities at one closed configuration.

    Attributes:
        q: (nq,) closed configuration.
        position: (3,) world position of the measured frame [m].
        rotation: (3, 3) its orientation.
        jacobian: (6, n) derivative of ``[p_world; rotation (local)]`` w.r.t. parameters
            [m/m, m/rad, rad/m, rad/rad].
        breaks_closure: (n,) True for the parameters whose change would open a loop
            that the passive joints cannot close at this pose (all False for serial
            chains and loops that are not over-constrained).
    """

    q: np.ndarray
    position: np.ndarray
    rotation: np.ndarray
    jacobian: np.ndarray
    breaks_closure: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))


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


def _breaking(solver: RangeSolver, Jc_p: np.ndarray) -> np.ndarray:
    """(n,) True where a closure column has a part outside range(∂c/∂q_u).

    A column breaks closure when that part exceeds :data:`RANK_RTOL` of the column's
    own norm (and is not round-off of a negligible column: 1e-12 of the largest).
    """
    if solver.rank == Jc_p.shape[0]:  # full row rank: every column is in the range
        return np.zeros(Jc_p.shape[1], dtype=bool)
    norms = np.linalg.norm(Jc_p, axis=0)
    out = solver.out_of_range(Jc_p)
    floor = 1e-12 * float(norms.max(initial=0.0))
    return (out > RANK_RTOL * norms) & (out > floor)


@dataclass(frozen=True)
class JacobianPlan:
    """What the sensitivity of one (mechanism, parameter set) pair needs, computed once.

    Attributes:
        frames: frames whose placement is needed: the key frames (measured + closure
            frames) and the parameterised fixed joints.
        moves: per frame, the parameterised joints among its URDF ancestors.
        origins: per parameterised joint, how to get its origin's world placement:
            ``(fixed-joint frame id, -1, -1)`` or ``(-1, joint id, parent joint id)``.
    """

    frames: tuple[str, ...]
    moves: dict[str, tuple[str, ...]]
    origins: dict[str, tuple[int, int, int]]


def jacobian_plan(mech: Mechanism, params: ParameterSet) -> JacobianPlan:
    """Which parameterised joints move each key frame, and where their origins hang."""
    joints = set(params.joints)
    moves = {
        f: tuple(j for j in mech.tree.ancestors(mech.frame_link(f)) if j in joints)
        for f in mech.key_frames
    }
    origins = {}
    for j in params.joints:
        if mech.tree.joints[j].type == "fixed":
            origins[j] = (mech.frame_id(j), -1, -1)
        else:
            jid = mech.model.getJointId(j)
            origins[j] = (-1, jid, mech.model.parents[jid])
    fixed = [j for j, (fid, _, _) in origins.items() if fid >= 0]
    return JacobianPlan(tuple(dict.fromkeys([*mech.key_frames, *fixed])), moves, origins)


def pose_sensitivity(
    mech: Mechanism,
    params: ParameterSet,
    q: np.ndarray | Kinematics,
    values: np.ndarray | Linearisation | None = None,
    plan: JacobianPlan | None = None,
) -> PoseSensitivity:
    """Sensitivity of the measured frame at a closed configuration.

    Args:
        mech: the mechanism at parameter ``values`` (``params.apply(nominal, values)``);
            derivatives are with respect to those values (exact chain rule through exp6).
        params: the parameter set (n parameters).
        q: the closed configuration (nq,), or its :class:`Kinematics` when already computed.
        values: (n,) parameter values (default zeros), or their :class:`Linearisation`
            (``params.linearise(values)``: pass it when evaluating many poses).
        plan: the ``(mech, params)`` plan when evaluating many poses (computed if None).
    """
    lin = params.linearise(values)
    if params.joint_terms.size:
        raise ParameterError(
            f"joint terms ({params.names[params.joint_terms[0]]}, …) are differentiated by "
            f"sensitivities_batch, not pose by pose (instrument calibrations do not take them yet)"
        )
    twists = lin.joint_twists
    plan = plan or jacobian_plan(mech, params)
    kin = q if isinstance(q, Kinematics) else mech.kinematics(q, plan.frames)
    placements, joints = kin.placements, kin.joint_placements
    model = mech.model
    n = len(params)
    origins: dict[str, pin.SE3] = {}
    for j, (fid, jid, parent) in plan.origins.items():
        origins[j] = placements[j] if fid >= 0 else joints[parent] * model.jointPlacements[jid]
    cache: dict[str, np.ndarray] = {}

    def param_twist(frame: str) -> np.ndarray:
        """(6, n) local twist of ``frame`` per unit of each parameter."""
        if frame not in cache:
            P = np.zeros((6, n))
            moves = plan.moves[frame]
            if moves:
                oMf_inv = placements[frame].inverse()
                for j in moves:
                    cols, _, eff = twists[j]
                    P[:, cols] = (oMf_inv * origins[j]).action @ eff
            cache[frame] = P
        return cache[frame]

    oMm = placements[mech.measured_frame]
    J = measured_jacobian(oMm, param_twist(mech.measured_frame))
    if mech.closures:
        free = mech.free_dofs
        Jc_p = np.vstack(
            [
                c.jacobian(
                    placements[c.frame_a],
                    placements[c.frame_b],
                    param_twist(c.frame_a),
                    param_twist(c.frame_b),
                )
                for c in mech.closures
            ]
        )
        solver = RangeSolver.factor(kin.closure_jacobian[:, free], mech.options.rcond)
        dqu_dp = solver.solve(-Jc_p)
        breaks = _breaking(solver, Jc_p)
        Jm_u = measured_jacobian(oMm, kin.jacobians[mech.measured_frame])[:, free]
        J = J + Jm_u @ dqu_dp
    else:
        breaks = np.zeros(n, dtype=bool)
    return PoseSensitivity(kin.q.copy(), oMm.translation.copy(), oMm.rotation.copy(), J, breaks)
