"""Joint origins written into a copy of a Pinocchio model (no URDF text, no rebuild).

A geometric parameter moves the origin of a URDF joint: ``origin ← origin · D``
(:mod:`pincal.model.params._parameters`). Pinocchio's URDF parser turns the tree into

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
above j has already moved ``F_j`` with everything below it). Which placements lie
below each fixed joint depends on the tree only: :class:`PlacementTree` finds them once
per model and serves every model moved from it. The result equals the model built from
the URDF text with the moved origins (checked for every bundled and test machine in
``tests/model/test_placements.py``).
"""

from __future__ import annotations

from collections.abc import Mapping

import pinocchio as pin

from pincal.errors import ModelFileError

__all__ = ["PlacementTree"]


class PlacementTree:
    """The placements each URDF joint origin enters, in a model built from a URDF.

    Args:
        model: the Pinocchio model (read once; models moved from it share its tree).
    """

    def __init__(self, model: pin.Model):
        frames = model.frames
        children: dict[int, list[int]] = {}
        for i in range(1, len(frames)):
            children.setdefault(int(frames[i].parentFrame), []).append(i)
        joint_frame = {int(f.parentJoint): i for i, f in enumerate(frames) if f.type == pin.JOINT}
        #: movable URDF joint → Pinocchio joint id
        self.joints = {str(model.names[k]): k for k in range(1, model.njoints)}
        #: fixed URDF joint → (its frame, its body's joint, frames below it in the body
        #: (itself first), joints whose placement passes through it)
        self.fixed: dict[str, tuple[int, int, tuple[int, ...], tuple[int, ...]]] = {}
        for index, f in enumerate(frames):
            if f.type != pin.FIXED_JOINT or index == 0:
                continue
            below, stack = [], [index]
            while stack:
                i = stack.pop()
                below.append(i)
                stack += [c for c in children.get(i, ()) if frames[c].type != pin.JOINT]
            body, inside = int(f.parentJoint), set(below)
            joints = tuple(
                k
                for k in range(1, model.njoints)
                if int(model.parents[k]) == body
                and int(frames[joint_frame[k]].parentFrame) in inside
            )
            self.fixed[str(f.name)] = (index, body, tuple(below), joints)

    def moved(
        self, model: pin.Model, moves: Mapping[str, pin.SE3]
    ) -> tuple[pin.Model, set[int], set[int]]:
        """A copy of ``model`` with URDF joint origins moved: ``origin ← origin · D``.

        Args:
            model: a model with this tree (the one it was made from, or moved from it).
            moves: URDF joint name → ``D``, the displacement of its origin expressed in
                the joint's own (unmoved) frame [m].

        Returns:
            The moved copy (joint placements, frame placements, body inertias), the ids
            of the joints and the indices of the frames whose placements moved.

        Raises:
            ModelFileError: a name that is neither a joint nor a fixed-joint frame of the
                model (e.g. a floating joint, which has no origin parameter).
        """
        new = model.copy()
        joints: set[int] = set()
        frames: set[int] = set()
        for name, D in moves.items():
            if name in self.joints:
                k = self.joints[name]
                new.jointPlacements[k] = new.jointPlacements[k] * D
                joints.add(k)
            elif name in self.fixed:
                index, body, below, inside = self.fixed[name]
                self._move_fixed(new, index, body, below, inside, D)
                joints.update(inside)
                frames.update(below)
            else:
                raise ModelFileError(
                    f"joint {name!r} is neither a joint nor a fixed-joint frame of the "
                    "Pinocchio model: its origin cannot be moved"
                )
        return new, joints, frames

    @staticmethod
    def _move_fixed(model: pin.Model, index: int, body: int, below: tuple[int, ...],
                    joints: tuple[int, ...], D: pin.SE3) -> None:  # fmt: skip
        """Left-multiply every placement below fixed-joint frame ``index`` in its body."""
        frames = model.frames
        F = frames[index].placement
        L = F * D * F.inverse()
        inertia = model.inertias[body]
        for i in below:
            f = frames[i]
            if f.inertia.mass > 0:
                inertia = inertia - f.placement.act(f.inertia) + (L * f.placement).act(f.inertia)
            f.placement = L * f.placement
        model.inertias[body] = inertia
        for k in joints:
            model.jointPlacements[k] = L * model.jointPlacements[k]
