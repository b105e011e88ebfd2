"""What a parameter does, in words a person can use: its direction in the parent link.

A parameter's name follows the joint-origin frame, i.e. the parent link's axes turned by
the origin's ``rpy`` (``base1.tx`` moves the joint along the *origin's* x). What a
person knows is the parent link's frame ("the forearm is along the upper arm's z").
:func:`parent_direction` turns a parameter's unit twist ``[v; ω]`` into that frame:
a translation along ``R·v`` or a rotation about ``R·ω`` (R: the origin's rotation),
the first-order effect of ``origin ← origin · exp6(δ·ξ)``.

Preset entries may select parameters by this direction (see
:func:`pincal.model.parameters`)::

    {joints: elbow*, along_parent: z}          # the translation along parent z
    {joints: base1, about_parent: [0, 0, 1]}   # the rotation about parent z
    {joints: elbow*, along_parent: z, hold: true}   # leave it out of the set
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pinocchio as pin

from pincal.errors import ParameterError
from pincal.model._mechanism import Mechanism

__all__ = [
    "AXIS_WORDS",
    "describe_direction",
    "direction_record",
    "matching_dofs",
    "parent_direction",
]

#: words accepted for a parent-frame axis
AXIS_WORDS = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}
#: |cos| of the angle between two directions taken as parallel
_PARALLEL = 1 - 1e-9


def parent_direction(mech: Mechanism, joint: str, twist: np.ndarray) -> tuple[str, np.ndarray]:
    """("translation" or "rotation", unit direction (3,) in the parent link's frame).

    A joint-space term (compliance, gain…: zero twist) gives ("joint term", zeros).

    Args:
        mech: the mechanism.
        joint: the URDF joint.
        twist: the parameter's unit twist ``[v; ω]`` in the joint-origin frame
            (``Parameter.twist``).
    """
    R = mech.tree.joints[joint].origin.rotation
    v, w = np.asarray(twist[:3], dtype=float), np.asarray(twist[3:], dtype=float)
    if np.linalg.norm(w) > 0:
        return "rotation", R @ w / np.linalg.norm(w)
    if np.linalg.norm(v) == 0:
        return "joint term", np.zeros(3)
    return "translation", R @ v / np.linalg.norm(v)


def _vec(d: np.ndarray) -> str:
    """``[a, b, c]`` rounded to 1e-4 (a -1.570796 rad rpy leaves 3e-7 crumbs), no -0."""
    return "[" + ", ".join(f"{round(float(x), 4) + 0.0:g}" for x in d) + "]"


def describe_direction(mech: Mechanism, name: str, joint: str, dof: str, twist: np.ndarray) -> str:
    """One line: what the parameter moves, in the joint-origin and the parent frame."""
    kind, d = parent_direction(mech, joint, twist)
    if kind == "joint term":
        return f"{name} = joint-space term '{dof}' of {joint} (changes its value, not its origin)"
    uj = mech.tree.joints[joint]
    rpy = pin.rpy.matrixToRpy(uj.origin.rotation)
    word = "along" if kind == "translation" else "about"
    if dof == "offset":
        local = f"{kind} {word} the joint axis {_vec(uj.axis)}"
    else:
        local = f"{kind} {word} origin {dof[1]}"
    turned = f" turned by the origin rpy {_vec(rpy)}" if np.any(np.abs(rpy) > 1e-12) else ""
    parent = f" ({uj.parent})"
    return f"{name} = {local}{turned} → {word} parent{parent} direction {_vec(d)}"


def direction_record(mech: Mechanism, name: str, joint: str, dof: str, twist: np.ndarray) -> dict:
    """The JSON form: name, kind, parent link, unit direction in it, the sentence."""
    kind, d = parent_direction(mech, joint, twist)
    return {
        "name": name,
        "kind": kind,
        "parent": mech.tree.joints[joint].parent,
        "parent_direction": [round(float(x), 12) + 0.0 for x in d],
        "text": describe_direction(mech, name, joint, dof, twist),
    }


def _axis(value: Any, key: str) -> np.ndarray:
    vec = AXIS_WORDS.get(value) if isinstance(value, str) else value
    try:
        a = np.asarray(vec, dtype=float)
    except (TypeError, ValueError):
        a = np.zeros(0)
    if a.shape != (3,) or not np.all(np.isfinite(a)) or np.linalg.norm(a) == 0:
        raise ParameterError(
            f"{key} must be x, y, z or a non-zero direction [a, b, c], got {value!r}"
        )
    return a / np.linalg.norm(a)


def matching_dofs(
    mech: Mechanism, joint: str, dofs: Sequence[tuple[str, np.ndarray]], key: str, value: Any
) -> list[str]:
    """The dofs of ``joint`` (name, twist) moving along / about ``value`` in the parent frame.

    Args:
        mech: the mechanism.
        joint: the URDF joint.
        dofs: its candidate dofs, (name, unit twist) each.
        key: ``along_parent`` (translations) or ``about_parent`` (rotations).
        value: ``x``, ``y``, ``z`` or a direction [a, b, c] (sign ignored).

    Raises:
        ParameterError: a bad direction, or none of the joint's dofs is parallel to it
            (the directions it has are listed).
    """
    want = _axis(value, key)
    kind = "translation" if key == "along_parent" else "rotation"
    found, have = [], []
    for dof, twist in dofs:
        k, d = parent_direction(mech, joint, twist)
        if k != kind:
            continue
        have.append(f"{joint}.{dof} {_vec(d)}")
        if abs(float(d @ want)) >= _PARALLEL:
            found.append(dof)
    if not found:
        raise ParameterError(
            f"joint {joint!r} has no {kind} {'along' if kind == 'translation' else 'about'} "
            f"parent direction {_vec(want)}; its {kind}s in the parent frame are: "
            + "; ".join(have)
        )
    return found
