"""Random feasible measurement poses inside a mechanism's workspace."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from pincal.errors import ConvergenceError, PincalError
from pincal.model._mechanism import Mechanism

__all__ = ["sample_actuators", "sample_pose"]


def _joint_ranges(mech: Mechanism) -> np.ndarray:
    ranges = np.array(mech.actuator_limits, dtype=float)
    for k, name in enumerate(mech.actuated):
        if name in mech.workspace.joints:
            ranges[k] = mech.workspace.joints[name]
    ranges[~np.isfinite(ranges[:, 0]), 0] = -np.pi
    ranges[~np.isfinite(ranges[:, 1]), 1] = np.pi
    return ranges


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
    forward kinematics converges away from singularities. Infeasible draws are
    rejected.
    """
    rows: list[np.ndarray] = []
    tries = 0
    ranges = _joint_ranges(mech)
    use_pose = bool(mech.workspace.pose)
    while len(rows) < n:
        tries += 1
        if tries > max_tries_per_pose * n:
            raise PincalError(
                f"only {len(rows)} of {n} random poses were feasible for {mech.name!r}; "
                "check the sidecar workspace limits"
            )
        try:
            if use_pose:
                q_act = mech.inverse(sample_pose(mech, rng))
            else:
                q_act = rng.uniform(ranges[:, 0], ranges[:, 1])
                mech.configuration(q_act)
        except ConvergenceError:
            continue
        rows.append(q_act)
    return np.array(rows)
