"""Branch changes of inverse kinematics: when a command leaves the branch of its start.

Compensation starts each target's inverse kinematics from a *start command* (the
target's own nominal command, or the nearest solved one). A calibration moves the
machine by millimetres and milliradians, so the compensated command must stay next to
its start. It is said to be on **another branch** when either

1. some actuator moved more than the step bound from the start. When the start is the
   target's own nominal command: |Δq| > 0.5 rad for a revolute actuator, > 50 mm for a
   prismatic one (:data:`BRANCH_STEP_RAD`, :data:`BRANCH_STEP_M`). When it is another
   target's command (nearest solved, or home), the targets themselves lie apart, so
   only a revolute |Δq| > π counts (:data:`FAR_STEP_RAD`: a half turn, the same pose
   being nearer the other way round). A 2π turn of a revolute joint counts either way:
   the same tip pose but a different arm motion. Or
2. the actuator → imposed-components Jacobian G = ∂(pose components)/∂q_act is square
   and det G changes sign between start and solution: the solution lies across a
   singularity (another elbow / shoulder / wrist configuration of an arm, another
   working mode of a parallel machine). G is the analytic actuator Jacobian through the
   loop closure (:func:`pincal.model.actuator_jacobian`); a sign is only trusted when
   |det G| exceeds 1e-6 of the product of G's column norms (else "unknown", not a change).
"""

from __future__ import annotations

import numpy as np

from pincal.errors import ConvergenceError
from pincal.model import Mechanism, actuator_difference, actuator_jacobian

__all__ = [
    "BRANCH_STEP_M",
    "BRANCH_STEP_RAD",
    "FAR_STEP_RAD",
    "actuator_units",
    "branch_change",
    "det_sign",
    "unwrapped",
]

#: largest |Δq| of a revolute actuator that stays on the start's branch [rad]
BRANCH_STEP_RAD = 0.5
#: largest |Δq| of a prismatic actuator that stays on the start's branch [m]
BRANCH_STEP_M = 0.05
#: largest revolute |Δq| from another target's command that stays on its branch [rad]
FAR_STEP_RAD = np.pi
_SIGN_FLOOR = 1e-6  # |det G| / Π‖G_j‖ below this: sign unknown


def actuator_units(mech: Mechanism) -> tuple[str, ...]:
    """``"rad"`` per revolute / continuous actuator, ``"m"`` per prismatic one (n_act,)."""
    return tuple(
        "rad" if mech.tree.joints[j].type in ("revolute", "continuous") else "m"
        for j in mech.actuated
    )


def unwrapped(mech: Mechanism, q_act: np.ndarray, start: np.ndarray) -> np.ndarray:
    """``q_act`` (n_act,) with each continuous actuator's angle taken nearest ``start``.

    A continuous joint's angle reads back in (−π, π]: a solution a few mrad past ±π from
    a start on the other side reads 2π away from it; the command is the same angle taken
    within π of the start [rad] (:func:`pincal.model.actuator_difference`).
    """
    start = np.asarray(start, dtype=float)
    moved = actuator_difference(mech, q_act, start)
    return np.where(np.isfinite(start), start + moved, np.asarray(q_act, dtype=float))


def det_sign(mech: Mechanism, q_act: np.ndarray, q: np.ndarray | None = None) -> int:
    """Sign of det G at ``q_act`` (G: actuators → ``mech``'s measured components).

    G is :func:`pincal.model.actuator_jacobian` at the closed configuration (the loops
    closed from ``q``), in the measurement residual's components (positions in world
    axes, rotations in the measured frame).

    Args:
        mech: the mechanism whose measured components are imposed.
        q_act: (n_act,) actuator values [m, rad].
        q: full configuration at ``q_act`` (used as it is when its loops are closed,
            else the guess of the closure), or None.

    Returns:
        +1 or -1; 0 when G is not square, (nearly) singular, or a closure fails.
    """
    n = len(q_act)
    if len(mech.measured_components) != n:
        return 0
    q_act = np.asarray(q_act, dtype=float)
    closed = (
        q is not None
        and np.allclose(mech.actuators_of(q), q_act, rtol=0.0, atol=1e-12)
        and float(np.linalg.norm(mech.closure_residual(q))) < 1e-10
    )
    try:
        q_closed = q if closed and q is not None else mech.configuration(q_act, q)
        G = actuator_jacobian(mech, q_closed)
    except ConvergenceError:
        return 0
    det = float(np.linalg.det(G))
    scale = float(np.prod(np.linalg.norm(G, axis=0)))
    if scale == 0.0 or abs(det) < _SIGN_FLOOR * scale:
        return 0
    return 1 if det > 0 else -1


def branch_change(
    mech: Mechanism,
    start: np.ndarray,
    solution: np.ndarray,
    q_start: np.ndarray | None,
    q_solution: np.ndarray,
    units: tuple[str, ...],
    own_start: bool = True,
) -> str:
    """Why ``solution`` is on another branch than ``start`` ("" when it is not).

    Args:
        mech: the mechanism whose measured components the compensation imposes.
        start: (n_act,) start command [m, rad].
        solution: (n_act,) solved command [m, rad].
        q_start: full configuration (nq,) of the start, or None.
        q_solution: full configuration (nq,) of the solution.
        units: :func:`actuator_units` of ``mech``.
        own_start: ``start`` is the target's own nominal command (tight step bounds);
            False: another target's command (only a revolute half turn counts).

    Returns:
        A sentence naming the criterion (see the module docstring), or "".
    """
    dq = np.abs(np.asarray(solution, float) - np.asarray(start, float))
    if own_start:
        bound = np.array([BRANCH_STEP_RAD if u == "rad" else BRANCH_STEP_M for u in units])
    else:
        bound = np.array([FAR_STEP_RAD if u == "rad" else np.inf for u in units])
    over = np.nonzero(dq > bound)[0]
    if over.size:
        k = int(over[np.argmax(dq[over] / bound[over])])
        shown = f"{dq[k]:.4g} rad" if units[k] == "rad" else f"{dq[k] * 1e3:.4g} mm"
        limit = f"{bound[k]:.4g} rad" if units[k] == "rad" else f"{bound[k] * 1e3:.4g} mm"
        return f"actuator {mech.actuated[k]} moved {shown} from its start (bound {limit})"
    s0 = det_sign(mech, np.asarray(start, float), q_start)
    s1 = det_sign(mech, np.asarray(solution, float), q_solution)
    if s0 and s1 and s0 != s1:
        return (
            "det of the actuator → pose Jacobian changed sign between start and solution "
            "(a singularity lies between them)"
        )
    return ""
