"""The floor under a robot standing on its base: drawn poses keep the links above it.

A sidecar's ``workspace: {floor: h}`` [m] asks that, in every drawn pose
(:func:`pincal.sample_actuators`, the joint grid of ``pincal poses``), every *moving*
point of the robot — each joint origin and each link frame (URDF links and joints,
the measured frame) whose height the actuated joints change — lies at least ``h``
above the base plane z = 0 of the model's root frame. Points the actuators cannot
raise or lower (the base, the first joint's origin on a vertical axis, a locked
torso) are not checked. ``floor: false`` (or no key) checks nothing.

Points are frame origins, not link surfaces: the margin ``h`` stands in for the
links' thickness. A robot by name from example-robot-data (no pincal sidecar) standing
on its base gets :data:`DEFAULT_FLOOR` unless its sidecar's workspace has a ``floor``
key; a robot hanging below its root link at home (a humanoid's arm: a moving point
more than that margin below z = 0) gets none.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from pincal.model._mechanism import Mechanism
from pincal.model.loops import six_by_nv

__all__ = ["DEFAULT_FLOOR", "above_floor", "moving_points", "point_heights", "stands_on_base"]

#: default floor margin for robots by name [m] (about a wrist's radius)
DEFAULT_FLOOR = 0.05
#: a height derivative below this [m/rad or m/m] is no motion
_STILL = 1e-9


def moving_points(mech: Mechanism) -> np.ndarray:
    """Frame indices (G,) whose height the actuated joints change.

    Decided from the height rows of the frames' Jacobians at home and at home moved
    by 0.3 rad (or m) on every actuated joint (a height can be still at one pose only).
    """
    model, data = mech.model, mech.model.createData()
    cols = [model.idx_vs[model.getJointId(n)] for n in mech.actuated]
    q1 = mech.with_actuators(mech.q_home, mech.actuators_of(mech.q_home) + 0.3)
    moving = np.zeros(model.nframes, dtype=bool)
    for q in (mech.q_home, q1):
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        for f in range(model.nframes):
            if moving[f] or model.frames[f].parentJoint == 0:
                continue
            J = six_by_nv(pin.getFrameJacobian(model, data, f, pin.LOCAL_WORLD_ALIGNED))
            moving[f] = bool(np.abs(J[2, cols]).max(initial=0.0) > _STILL)
    return np.flatnonzero(moving)


def point_heights(mech: Mechanism, q: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Heights z (G,) [m] of frames ``points`` in the root frame at configuration q (nq,)."""
    data = mech.model.createData()
    pin.framesForwardKinematics(mech.model, data, q)
    return np.array([data.oMf[int(f)].translation[2] for f in points])


def stands_on_base(mech: Mechanism) -> bool:
    """Whether no moving point is more than :data:`DEFAULT_FLOOR` below z = 0 at home.

    (ur5's wrist is 5.5 mm below its base plane at q = 0; talos' hand hangs 0.3 m
    below its pelvis.)
    """
    points = moving_points(mech)
    low = point_heights(mech, mech.q_home, points).min(initial=np.inf)
    return bool(low >= -DEFAULT_FLOOR)


def above_floor(
    mech: Mechanism, q_act_rows: np.ndarray, points: np.ndarray | None = None
) -> np.ndarray:
    """Whether each actuator row (N, n_act) keeps the moving points above the floor (N,).

    All True when the mechanism's ``workspace.floor`` is None. Open chains only (the
    other joints at their home values); a closed mechanism is not checked (all True).
    ``points``: :func:`moving_points` when already computed.
    """
    rows = np.atleast_2d(np.asarray(q_act_rows, dtype=float))
    floor = mech.workspace.floor
    ok = np.ones(rows.shape[0], dtype=bool)
    if floor is None or mech.closures or rows.shape[0] == 0:
        return ok
    points = moving_points(mech) if points is None else points
    for k, row in enumerate(rows):
        q = mech.with_actuators(mech.q_home, row)
        ok[k] = bool(point_heights(mech, q, points).min(initial=np.inf) >= floor)
    return ok
