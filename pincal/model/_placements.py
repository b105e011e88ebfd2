"""Joint origins written into a copy of a Pinocchio model (no URDF text, no rebuild).

A geometric parameter moves the origin of a URDF joint: ``origin ← origin · D``
(:mod:`pincal.model._parameters`). Pinocchio's URDF parser turns the tree into

* a joint per movable URDF joint, placed relative to its parent joint by the product of
  the origins from that parent's child link down to it (fixed joints between them are
  merged away): ``jointPlacements[k] = A · O_k``;
* a frame per URDF joint and link, placed relative to its parent joint by the same kind
  of product: ``frames[f].placement = A · O_j · B``; a fixed joint's frame carries its
  child link's inertia ``Y``, added to the parent joint's body as ``placement.act(Y)``;
* ``parentFrame`` links that follow the URDF tree inside each body.

So moving a movable joint's origin right-multiplies its joint placement by ``D`` (its
frames hang from the joint and do not move relative to it), and moving a fixed joint
j (frame placement ``F_j``) left-multiplies every placement below it inside its body by
``L = F_j · D · F_j⁻¹`` (``A O_j B → A O_j D B``), the inertia it carries included.
``F_j`` is read when j is moved, so the order of the moves does not matter (a move
above j has already moved ``F_j`` with everything below it). The result equals the model built from the URDF text with
the moved origins (checked for every bundled and test machine in
``tests/model/test_placements.py``).
"""

from __future__ import annotations

from collections.abc import Mapping

import pinocchio as pin

from pincal.errors import ModelFileError

__all__ = ["moved_model"]


def moved_model(model: pin.Model, moves: Mapping[str, pin.SE3]) -> pin.Model:
    """A copy of ``model`` with URDF joint origins moved: ``origin ← origin · D``.

    Args:
        model: the Pinocchio model built from a URDF (not modified).
        moves: URDF joint name → ``D``, the displacement of its origin expressed in the
            joint's own (unmoved) frame [m].

    Returns:
        The moved copy (joint placements, frame placements, body inertias).

    Raises:
        ModelFileError: a name that is neither a joint nor a fixed-joint frame of the
            model (e.g. a floating joint, which has no origin parameter).
    """
    new = model.copy()
    frames = new.frames
    children: dict[int, list[int]] = {}
    for i in range(1, len(frames)):
        children.setdefault(int(frames[i].parentFrame), []).append(i)
    fixed = {frames[i].name: i for i in range(len(frames)) if frames[i].type == pin.FIXED_JOINT}
    joint_frame = {
        int(frames[i].parentJoint): i for i in range(len(frames)) if frames[i].type == pin.JOINT
    }
    for name in moves:
        D = moves[name]
        if new.existJointName(name):
            k = new.getJointId(name)
            new.jointPlacements[k] = new.jointPlacements[k] * D
            continue
        if name not in fixed:
            raise ModelFileError(
                f"joint {name!r} is neither a joint nor a fixed-joint frame of the Pinocchio "
                "model: its origin cannot be moved"
            )
        _move_fixed(new, fixed[name], D, children, joint_frame)
    return new


def _move_fixed(
    model: pin.Model,
    index: int,
    D: pin.SE3,
    children: Mapping[int, list[int]],
    joint_frame: Mapping[int, int],
) -> None:
    """Left-multiply every placement below fixed-joint frame ``index`` in its body."""
    frames = model.frames
    body = int(frames[index].parentJoint)
    F = frames[index].placement
    L = F * D * F.inverse()
    below, stack = [], [index]
    while stack:
        i = stack.pop()
        below.append(i)
        stack += [c for c in children.get(i, ()) if frames[c].type != pin.JOINT]
    inertia = model.inertias[body]
    for i in below:
        f = frames[i]
        if f.inertia.mass > 0:
            placed = f.placement.act(f.inertia)
            inertia = inertia - placed + (L * f.placement).act(f.inertia)
        f.placement = L * f.placement
    model.inertias[body] = inertia
    for k in range(1, model.njoints):
        if int(model.parents[k]) == body and int(frames[joint_frame[k]].parentFrame) in below:
            model.jointPlacements[k] = L * model.jointPlacements[k]
