"""A mechanism's description read from its model and sidecar.

The loop closures, the measured frame, the actuated joints (and their limits) and the
workspace of a :class:`~pincal.model.Mechanism`, each checked against the Pinocchio
model and the URDF, with errors that name what is valid.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from pincal.errors import ModelFileError, UnknownNameError
from pincal.model.files import (
    Closure,
    Sidecar,
    UrdfTree,
    Workspace,
    default_measured_frame,
    parse_components,
)
from pincal.model.loops import KinematicQueries, frame_index

__all__ = [
    "actuator_limits",
    "closure_links",
    "parse_actuated",
    "parse_closures",
    "parse_workspace",
    "resolve_measured_frame",
]


def parse_closures(
    sidecar: Sidecar, frame_ids: dict[str, int], tree: UrdfTree
) -> tuple[Closure, ...]:
    """The sidecar's loop closures (their frames checked against ``frame_ids``)."""
    closures = []
    for k, ((a, b), kind) in enumerate(zip(sidecar.closed_loop, sidecar.type, strict=True)):
        frame_index(frame_ids, tree, a)
        frame_index(frame_ids, tree, b)
        comps = parse_components(kind, f"sidecar type[{k}]")
        label = kind if isinstance(kind, str) else " ".join(kind)
        closures.append(Closure(a, b, comps, label))
    return tuple(closures)


def closure_links(tree: UrdfTree, closures: tuple[Closure, ...]) -> set[str]:
    """URDF links the closure frames are attached to (a joint frame sits on its child)."""
    return {_link_of(tree, f) for c in closures for f in (c.frame_a, c.frame_b)}


def _link_of(tree: UrdfTree, frame: str) -> str:
    if frame in tree.joints and frame not in tree.links:
        return tree.joints[frame].child
    return frame


def resolve_measured_frame(
    requested: str | None,
    sidecar: Sidecar,
    tree: UrdfTree,
    closures: tuple[Closure, ...],
    frame_ids: dict[str, int],
    name: str,
) -> str:
    """The measured frame: ``requested``, else the sidecar's, else the automatic choice."""
    frame = requested or sidecar.measured_frame
    if frame is None:
        frame = default_measured_frame(tree, closure_links(tree, closures), name)
    frame_index(frame_ids, tree, str(frame))
    return str(frame)


def parse_actuated(
    model: pin.Model,
    sidecar: Sidecar,
    closures: tuple[Closure, ...],
    frame_ids: dict[str, int],
    measured_frame: str,
) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """The actuated joints (sidecar ``name_mot``, else an open chain's) and notes.

    Raises:
        ModelFileError: a closed-loop mechanism without ``name_mot``, or a joint listed
            twice.
        UnknownNameError: an actuated joint that is not a 1-dof joint of the model.
    """
    movable = [model.names[j] for j in range(1, model.njoints) if model.joints[j].nv == 1]
    names = sidecar.name_mot
    if names is None:
        if closures:
            raise ModelFileError(
                "a closed-loop mechanism needs 'name_mot' (actuated joints) in its sidecar"
            )
        return _chain_joints(model, movable, frame_ids[measured_frame], measured_frame)
    for n in names:
        if n not in movable:
            raise UnknownNameError("actuated joint", str(n), movable)
    if len(set(names)) != len(names):
        raise ModelFileError(f"sidecar 'name_mot' lists a joint twice: {names}")
    return tuple(str(n) for n in names), ()


def _chain_joints(
    model: pin.Model, movable: list[str], fid: int, measured_frame: str
) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """An open chain's actuated joints: the 1-dof joints that move the measured frame.

    The others (a gripper's fingers, a mobile manipulator's head) stay passive and
    idle: they are not actuated for calibration, and a note says so.
    """
    support = set(model.supports[model.frames[fid].parentJoint])
    chain = tuple(n for n in movable if model.getJointId(n) in support)
    off = [n for n in movable if n not in chain]
    if not off:
        return chain, ()
    shown = ", ".join(off[:6]) + (f" and {len(off) - 6} more" if len(off) > 6 else "")
    return chain, (
        f"{len(off)} joint(s) do not move the measured frame {measured_frame!r} and "
        f"are not actuated for calibration: {shown} (list the actuated joints in the "
        f"sidecar 'name_mot' to change this)",
    )


def actuator_limits(model: pin.Model, queries: KinematicQueries) -> np.ndarray:
    """(n_act, 2) lower and upper limits of the actuators (±inf for unbounded revolutes)."""
    lower, upper = [], []
    for qi, nq in zip(queries.act_q, queries.act_nq, strict=True):
        if nq == 1:
            lower.append(model.lowerPositionLimit[qi])
            upper.append(model.upperPositionLimit[qi])
        else:
            lower.append(-np.inf)
            upper.append(np.inf)
    return np.array([lower, upper]).T


def parse_workspace(sidecar: Sidecar, actuated: tuple[str, ...]) -> Workspace:
    """The sidecar's workspace (its joint ranges name actuated joints).

    Raises:
        UnknownNameError: a workspace joint range names a joint that is not actuated.
    """
    ws = sidecar.workspace
    for k in ws.joints:
        if k not in actuated:
            raise UnknownNameError("actuated joint", k, actuated)
    return Workspace(dict(ws.pose), dict(ws.joints), ws.floor)
