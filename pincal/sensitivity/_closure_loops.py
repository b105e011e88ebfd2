"""Which loop closures a parameter lies on, and the one line naming those that break them.

A loop closure joins two frames of the spanning tree; its loop is the tree path between
them: the URDF joints from each frame's link up to their last common ancestor (the
joints above it are shared by both frames and are not in the loop). A parameter lies on
a loop when the URDF joint whose origin it changes is on that path. Parameters that
break loop closure are said in one line grouped by these loops (:func:`closure_line`,
used by :class:`~pincal.sensitivity.Identifiability`'s ``describe``): a leg's joints on
its own loop, the joints shared by several loops apart.
"""

from __future__ import annotations

from pincal.model import Mechanism, ParameterSet

__all__ = ["ClosureLoop", "closure_line", "closure_loops"]

#: a loop closure's label (``"frame_a↔frame_b"``) and the indices of the parameters on it
ClosureLoop = tuple[str, tuple[int, ...]]


def _chain(mech: Mechanism, frame: str) -> list[str] | None:
    """URDF joints from ``frame``'s link up to the root (nearest first), or None.

    None when ``frame`` is neither a link nor a joint of the tree.
    """
    tree = mech.tree
    if frame in tree.links:
        link = frame
    elif frame in tree.joints:
        link = tree.joints[frame].child  # a joint frame sits on its child link
    else:
        return None
    out: list[str] = []
    while link in tree.parent_joint:
        joint = tree.parent_joint[link]
        out.append(joint)
        link = tree.joints[joint].parent
    return out


def closure_loops(mech: Mechanism, params: ParameterSet) -> tuple[ClosureLoop, ...]:
    """The loop of each of ``mech``'s closures and the parameters of ``params`` on it.

    Args:
        mech: the mechanism (its URDF tree and closures).
        params: the n parameters; a parameter's joint is the URDF joint whose origin it
            changes (``Parameter.joint``).

    Returns:
        One ``(label, indices)`` per closure, in the mechanism's order; () when a
        closure frame is not in the tree (the loops cannot be told).
    """
    out: list[ClosureLoop] = []
    for closure in mech.closures:
        a, b = _chain(mech, closure.frame_a), _chain(mech, closure.frame_b)
        if a is None or b is None:
            return ()
        on_loop = set(a) ^ set(b)
        members = tuple(k for k, p in enumerate(params.parameters) if p.joint in on_loop)
        out.append((f"{closure.frame_a}↔{closure.frame_b}", members))
    return tuple(out)


def closure_line(
    names: list[str], loops: tuple[tuple[str, tuple[str, ...]], ...] = (), max_joints: int = 4
) -> str:
    """One line for the parameters ``names`` that break loop closure, grouped by loop.

    For example (the Agile Eye, ``--params full``) ``"55 parameters break loop closure
    in 2 loops (no passive-joint motion can close the loops after changing them; not
    identifiable): loop wrist2↔seat2: 15 at 3 joints (base2.{tx ty tz rx ry},
    elbow2.{tx ty tz rx ry} and 1 more joint); loop wrist3↔seat3: …; shared by both
    loops: 25 at 5 joints (…)"``. Within a group, parameters are said by joint
    (``joint.{dofs}``), the first ``max_joints`` (``max_joints // 2`` per group when
    there are several). All on one loop: ``"18 parameters break loop closure at 6
    joints of loop a↔b (…): act_a.{…}, …"``. Without ``loops`` (or with a name on none
    of them), by joint alone: ``"… at 11 joints …: base1.{…}, … and 7 more joints"``.

    Args:
        names: the breaking parameters' names (``joint.dof``), at least one.
        loops: each closure's label and the names of the parameters on its loop
            (:func:`closure_loops`, by name).
        max_joints: joints shown by name.
    """
    n = len(names)
    verb, them = ("parameter breaks", "it") if n == 1 else ("parameters break", "them")
    why = (f"(no passive-joint motion can close the loops after changing {them}; "
           "not identifiable)")  # fmt: skip
    groups = _loop_groups(names, loops)
    if len(groups) <= 1:
        joints = _by_joint(names)
        at = f" at {len(joints)} joints" if len(joints) > 1 else ""
        if groups:  # one loop: "at 6 joints of loop a↔b", "in loop a↔b"
            at += f" of {groups[0][0]}" if at else f" in {groups[0][0]}"
        return f"{n} {verb} loop closure{at} {why}: {_joints_text(joints, max_joints)}"
    per, parts = max(1, max_joints // 2), []
    for label, members in groups:
        joints = _by_joint(members)
        at = f" at {len(joints)} joints" if len(joints) > 1 else ""
        parts.append(f"{label}: {len(members)}{at} ({_joints_text(joints, per)})")
    n_loops = sum(any(m in on for m in names) for _, on in loops)
    return f"{n} {verb} loop closure in {n_loops} loops {why}: " + "; ".join(parts)


def _loop_groups(
    names: list[str], loops: tuple[tuple[str, tuple[str, ...]], ...]
) -> list[tuple[str, list[str]]]:
    """``names`` by the set of loops they lie on, each group's label first.

    Each loop's own parameters first, in the loops' order, then those shared by several
    loops; [] when a name lies on no loop (or no loops are given).
    """
    keys: dict[tuple[int, ...], list[str]] = {}
    for name in names:
        on = tuple(i for i, (_, members) in enumerate(loops) if name in members)
        if not on:
            return []
        keys.setdefault(on, []).append(name)
    used = {i for key in keys for i in key}
    out = []
    for key in sorted(keys, key=lambda t: (len(t), t)):
        labels = [loops[i][0] for i in key]
        if len(key) == 1:
            label = f"loop {labels[0]}"
        elif len(key) == len(used):
            label = "shared by both loops" if len(key) == 2 else f"shared by all {len(key)} loops"
        else:
            label = f"shared by loops {', '.join(labels)}"
        out.append((label, keys[key]))
    return out


def _by_joint(names: list[str]) -> dict[str, list[str]]:
    """Parameter names grouped by their joint (``joint.dof``), in first-use order."""
    joints: dict[str, list[str]] = {}
    for name in names:
        joint, _, dof = name.rpartition(".")
        joints.setdefault(joint or name, []).append(dof if joint else "")
    return joints


def _joints_text(joints: dict[str, list[str]], max_joints: int) -> str:
    """``base1.{tx ty tz}, elbow1.rx and 3 more joints``: the first ``max_joints``."""
    shown = [f"{j}.{{{' '.join(d)}}}" if len(d) > 1 else (f"{j}.{d[0]}" if d[0] else j)
             for j, d in list(joints.items())[:max_joints]]  # fmt: skip
    more = len(joints) - len(shown)
    tail = f" and {more} more joint{'s' if more > 1 else ''}" if more else ""
    return ", ".join(shown) + tail
