"""Random feasible measurement poses inside a mechanism's workspace.

A pose drawn in a ``pose`` workspace is kept only when the forward kinematics of its
inverse-kinematics solution (on home's assembly branch, what every later step uses)
returns it: a pose reached only on another assembly mode (a mirrored platform, the
other elbow of a five-bar) would otherwise give data for a different pose.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from pincal.errors import ConvergenceError, ModelFileError, UnreachablePoseError
from pincal.model._mechanism import Mechanism
from pincal.model.files import COMPONENTS
from pincal.model.reach._floor import above_floor, moving_points
from pincal.model.reach._range_explore import explored_ranges

__all__ = ["sample_actuators", "sample_pose"]


#: a pose whose forward kinematics misses the drawn target by more [m, rad] is refused
_ROUND_TRIP_TOL = 1e-6


def joint_ranges(mech: Mechanism) -> np.ndarray:
    """(n_act, 2) sampling ranges [m, rad].

    The sidecar workspace, else the URDF limits, else (no range declared) the range
    explored from home (:mod:`pincal.model.reach._range_explore`); a mechanism without loops
    falls back to ±π for what is still unlimited.
    """
    ranges = np.array(mech.actuator_limits, dtype=float)
    for k, name in enumerate(mech.actuated):
        if name in mech.workspace.joints:
            ranges[k] = mech.workspace.joints[name]
    if mech.closures:
        for k, bounds in explored_ranges(mech).items():
            ranges[k] = bounds
    ranges[~np.isfinite(ranges[:, 0]), 0] = -np.pi
    ranges[~np.isfinite(ranges[:, 1]), 1] = np.pi
    with np.errstate(over="ignore"):
        width = ranges[:, 1] - ranges[:, 0]
    bad = np.flatnonzero(~(np.isfinite(width) & (width >= 0)))
    if bad.size:
        k = int(bad[0])
        raise ModelFileError(
            f"joint {mech.actuated[k]!r} of {mech.name!r} has the range "
            f"[{ranges[k, 0]:.6g}, {ranges[k, 1]:.6g}] to sample in; give finite limits with "
            f"lower <= upper (URDF <limit> or the sidecar workspace 'joints')"
        )
    return ranges


def _off_branch(mech: Mechanism, q_act: np.ndarray, target: pin.SE3) -> bool:
    """Whether forward kinematics on home's branch misses the IK target (another mode)."""
    reached = mech.forward(q_act)
    error = np.concatenate(
        [reached.translation - target.translation, pin.log3(target.rotation.T @ reached.rotation)]
    )
    comps = [COMPONENTS.index(c) for c in mech.measured_components]
    return bool(np.max(np.abs(error[comps])) > _ROUND_TRIP_TOL)


def sample_pose(mech: Mechanism, rng: np.random.Generator) -> pin.SE3:
    """A random measured-frame pose within ``mech.workspace.pose`` (home for missing keys)."""
    home = mech.frame_placement(mech.q_home)
    lim = mech.workspace.pose
    p = home.translation.copy()
    for i, key in enumerate("xyz"):
        if key in lim:
            p[i] = rng.uniform(*lim[key])
    r = np.array([rng.uniform(*lim[k]) if k in lim else 0.0 for k in ("rx", "ry", "rz")])
    return pin.SE3(home.rotation @ pin.exp3(r), p)


def sample_actuators(
    mech: Mechanism, n: int, rng: np.random.Generator, max_tries_per_pose: int = 50
) -> np.ndarray:
    """``n`` random feasible actuator rows (n, n_act).

    With a pose workspace, poses are drawn uniformly in it and solved by inverse
    kinematics; otherwise actuator values are drawn in their ranges and kept when the
    forward kinematics converges away from singularities (in blocks closed by the
    batched solve where the mechanism allows it, else one by one). Infeasible draws
    are rejected, and so are poses reached only in another assembly mode than home's
    and, for an open chain with a ``workspace.floor``, poses with a moving link frame
    below the floor (:mod:`pincal.model.reach._floor`).

    Raises:
        ModelFileError: fewer than ``n`` feasible poses in ``max_tries_per_pose · n``
            draws (the message says when the workspace lies on another assembly mode),
            or an actuator range that is not finite or inverted.
    """
    ranges = joint_ranges(mech)
    use_pose = bool(mech.workspace.pose)
    if not use_pose and mech.batch_solvable:
        return _screened_draws(mech, n, rng, ranges, max_tries_per_pose * n)
    rows: list[np.ndarray] = []
    tries = mirrored = 0
    points = moving_points(mech) if mech.workspace.floor is not None else None
    while len(rows) < n:
        tries += 1
        if tries > max_tries_per_pose * n:
            raise ModelFileError(_infeasible(mech, len(rows), n, mirrored, tries - 1))
        try:
            if use_pose:
                target = sample_pose(mech, rng)
                q_act = mech.inverse(target)
                if _off_branch(mech, q_act, target):
                    mirrored += 1
                    continue
            else:
                q_act = rng.uniform(ranges[:, 0], ranges[:, 1])
                mech.configuration(q_act)
        except UnreachablePoseError as exc:
            # residual 0: IK converged, but only in another assembly mode than home's
            mirrored += exc.residual == 0.0
            continue
        except ConvergenceError:
            continue
        if points is not None and not above_floor(mech, q_act, points)[0]:
            continue  # a link through the floor (workspace.floor)
        rows.append(q_act)
    return np.array(rows)


def _screened_draws(
    mech: Mechanism, n: int, rng: np.random.Generator, ranges: np.ndarray, max_draws: int
) -> np.ndarray:
    """``n`` feasible actuator rows drawn in their ranges, screened in blocks.

    Each block of draws is decided by :meth:`Mechanism.closable_batch` (feasible: forward
    kinematics on home's branch away from singularities, as one by one). Infeasible
    draws (actuator values no assembly reaches) then mostly cost one batched solve
    together, instead of a pose-by-pose continuation each that fails only after
    halving its step 12 times.
    """
    rows: list[np.ndarray] = []
    draws = 0
    while len(rows) < n:
        if draws >= max_draws:
            raise ModelFileError(_infeasible(mech, len(rows), n, 0, draws))
        rate = (len(rows) + 1) / (draws + 1)  # share of feasible draws so far
        size = min(max_draws - draws, 4096, max(32, int(1.5 * (n - len(rows)) / rate)))
        block = rng.uniform(ranges[:, 0], ranges[:, 1], size=(size, len(ranges)))
        draws += size
        ok = mech.closable_batch(block)
        rows.extend(block[ok][: n - len(rows)])
    return np.array(rows)


def _infeasible(mech: Mechanism, got: int, n: int, mirrored: int, tries: int) -> str:
    floor = mech.workspace.floor
    text = (
        f"only {got} of {n} random poses were feasible for {mech.name!r} ({tries} draws); "
        "check the sidecar workspace limits"
    )
    if floor is not None:
        text += f" and its floor ({floor:.3g} m above the base plane; 'floor: false' drops it)"
    if mirrored:
        text += (
            f": {mirrored} drawn poses are reached only in another assembly mode than home's "
            "(e.g. the platform mirrored through the base), where forward kinematics would "
            "not return them; give a 'pose' workspace on home's side (home's measured frame "
            f"is at {np.round(mech.frame_placement(mech.q_home).translation, 4).tolist()} m)"
        )
    return text
