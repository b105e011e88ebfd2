"""Serial chains: base and tool frames as parameters, locked joints.

Base and tool frames
--------------------
A measuring instrument (laser tracker, CMM) reports points in its own frame, which
is not the robot's base frame; and the measured point (a tracker target, a probe
centre) is not the robot's flange. Both are constant rigid transforms, so both are
URDF fixed joints whose origins pincal can displace like any other placement:
:func:`wrap_base_tool` adds

- a new root link ``instrument`` and a fixed joint ``base_frame`` from it to the
  URDF's old root: its origin is ``T_instrument_base``; its six parameters
  ``base_frame.tx … .rz`` are the base frame;
- a fixed joint ``tool_frame`` from the flange link to a new link ``tool`` (the
  measured frame): its origin is ``T_flange_tool``; its parameters are the tool frame.

A URDF joint origin twist on the *first* joint already moves everything downstream,
so ``base_frame`` and the first joint's origin are exactly redundant (identification
reports one of them as absorbed); a dedicated joint keeps the names meaningful and
lets the instrument frame be set without touching the robot's own geometry.

Registration of the instrument frame (a closed-form first guess of ``base_frame``) is
:func:`pincal.measure.register_instrument`.

Locked joints
-------------
:func:`lock_joints` turns movable joints (e.g. the Panda's two finger joints, one of
which mimics the other) into fixed joints at given values, so they are neither
actuated nor measured.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import pinocchio as pin

from pincal._files import read_text
from pincal.errors import ModelFileError, UnknownNameError
from pincal.model._mechanism import Mechanism
from pincal.model.files import MOVABLE_TYPES, UrdfTree
from pincal.model.loading._lock_values import lock_values_at_home
from pincal.model.loading._named import resolve_named
from pincal.model.loading._reroot import reroot_urdf

__all__ = [
    "BASE_JOINT",
    "INSTRUMENT_LINK",
    "TOOL_JOINT",
    "TOOL_LINK",
    "chain_preset",
    "lock_joints",
    "serial_mechanism",
    "with_joint_origin",
    "wrap_base_tool",
]

BASE_JOINT = "base_frame"
TOOL_JOINT = "tool_frame"
INSTRUMENT_LINK = "instrument"
TOOL_LINK = "tool"
_SIX = ["tx", "ty", "tz", "rx", "ry", "rz"]


def _origin_attrs(M: pin.SE3) -> dict[str, str]:
    rpy = pin.rpy.matrixToRpy(M.rotation)
    return {
        "xyz": " ".join(repr(float(v)) for v in M.translation),
        "rpy": " ".join(repr(float(v)) for v in rpy),
    }


def _parse(urdf_xml: str) -> ET.Element:
    UrdfTree(urdf_xml)  # validates (one tree, known links, numbers)
    return ET.fromstring(urdf_xml)


def lock_joints(urdf_xml: str, values: Mapping[str, float]) -> str:
    """URDF text with the named movable joints made fixed at the given values.

    A locked joint's origin becomes ``origin · motion(value)`` (a rotation about or a
    translation along its axis [rad or m]). Movable joints that ``<mimic>`` a locked
    joint are locked too, at ``multiplier · value + offset``; a ``<mimic>`` on a joint
    that is already fixed (PAL's TALOS and TIAGo grippers) has no effect and is dropped.

    Raises:
        UnknownNameError: a name is not a movable joint of the URDF.
    """
    tree = UrdfTree(urdf_xml)
    movable = [n for n, j in tree.joints.items() if j.movable]
    locked = {str(k): float(v) for k, v in values.items()}
    for name in locked:
        if name not in movable:
            raise UnknownNameError("movable joint", name, movable)
    root = ET.fromstring(urdf_xml)
    elements = {str(e.get("name")): e for e in root.findall("joint")}
    changed = True
    while changed:  # follow mimic chains
        changed = False
        for name, e in elements.items():
            mimic = e.find("mimic")
            leader = None if mimic is None else mimic.get("joint")
            if name in locked or mimic is None or leader is None or leader not in locked:
                continue
            if not tree.joints[name].movable:  # PAL URDFs: <mimic> on fixed joints, inert
                e.remove(mimic)
                continue
            mult = float(mimic.get("multiplier", "1"))
            off = float(mimic.get("offset", "0"))
            locked[str(name)] = mult * locked[leader] + off
            changed = True
    for name, value in locked.items():
        uj = tree.joints[name]
        motion = uj.offset_twist() * value
        M = uj.origin * pin.exp6(motion)
        e = elements[name]
        e.set("type", "fixed")
        for tag in ("axis", "limit", "mimic", "dynamics", "safety_controller", "calibration"):
            for child in e.findall(tag):
                e.remove(child)
        origin = e.find("origin")
        if origin is None:
            origin = ET.SubElement(e, "origin")
        origin.attrib.update(_origin_attrs(M))
    return ET.tostring(root, encoding="unicode")


def wrap_base_tool(
    urdf_xml: str,
    flange: str | None,
    T_instrument_base: pin.SE3 | None = None,
    T_flange_tool: pin.SE3 | None = None,
    base: bool = True,
) -> str:
    """URDF text with a base-frame joint above the root and a tool-frame joint on ``flange``.

    Args:
        urdf_xml: the robot's URDF.
        flange: link that carries the tool (e.g. ``tool0``); None for no tool frame.
        T_instrument_base: initial ``base_frame`` origin (default identity).
        T_flange_tool: initial ``tool_frame`` origin (default identity) [m].
        base: whether to add the base frame.

    Returns:
        URDF text; new names ``instrument`` (root link), ``base_frame`` (fixed joint),
        ``tool_frame`` (fixed joint) and ``tool`` (link, the natural measured frame).

    Raises:
        ModelFileError: a new name already exists in the URDF.
        UnknownNameError: ``flange`` is not a link.
    """
    tree = UrdfTree(urdf_xml)
    root = _parse(urdf_xml)
    taken = set(tree.links) | set(tree.joints)
    new = ([INSTRUMENT_LINK, BASE_JOINT] if base else []) + (
        [TOOL_LINK, TOOL_JOINT] if flange is not None else []
    )
    clash = sorted(taken.intersection(new))
    if clash:
        raise ModelFileError(f"cannot add base/tool frames: the URDF already has {clash}")
    if flange is not None and flange not in tree.links:
        raise UnknownNameError("link", flange, tree.links)

    def joint(name: str, parent: str, child: str, M: pin.SE3 | None) -> ET.Element:
        e = ET.Element("joint", {"name": name, "type": "fixed"})
        ET.SubElement(e, "parent", {"link": parent})
        ET.SubElement(e, "child", {"link": child})
        ET.SubElement(e, "origin", _origin_attrs(M if M is not None else pin.SE3.Identity()))
        return e

    if base:
        # the new root link must come first: Pinocchio takes the first root it finds
        root.insert(0, ET.Element("link", {"name": INSTRUMENT_LINK}))
        root.append(joint(BASE_JOINT, INSTRUMENT_LINK, tree.root_link, T_instrument_base))
    if flange is not None:
        root.append(ET.Element("link", {"name": TOOL_LINK}))
        root.append(joint(TOOL_JOINT, flange, TOOL_LINK, T_flange_tool))
    ET.indent(root)
    return ET.tostring(root, encoding="unicode")


def _axis_dof(axis: np.ndarray) -> str | None:
    """The rotation/translation dof name along a coordinate axis, if the axis is one."""
    for i, name in enumerate("xyz"):
        if np.allclose(np.abs(axis), np.eye(3)[i]):
            return name
    return None


def chain_preset(
    mech: Mechanism,
    base: bool = True,
    tool: bool | Sequence[str] = True,
    frame: str | None = None,
) -> list[dict[str, object]]:
    """Preset entries: base frame (6), every movable joint on the chain (origin + offset), tool.

    For each movable joint between the root and ``frame`` (default: the measured
    frame), its origin's six twists with the one along the motion axis replaced by
    the joint ``offset`` (encoder / prismatic zero). Fixed joints inside the chain are
    left out: each is exactly redundant with the next movable joint's origin.

    Args:
        mech: a mechanism (usually from :func:`serial_mechanism`).
        base: include ``base_frame`` (6 dofs) if the URDF has it.
        tool: include ``tool_frame``: True for 6 dofs, or a list of dofs
            (``["tx", "ty", "tz"]`` for a point probe measured by position only).
        frame: the chain's end link (default the measured frame).
    """
    tree = mech.tree
    end = frame or mech.measured_frame
    entries: list[dict[str, object]] = []
    if base and BASE_JOINT in tree.joints:
        entries.append({"joints": BASE_JOINT, "dofs": list(_SIX)})
    for name in tree.ancestors(end):
        uj = tree.joints[name]
        if uj.type not in MOVABLE_TYPES:
            continue
        dofs = list(_SIX)
        along = _axis_dof(uj.axis)
        if along is not None:
            dofs.remove(("r" if uj.type != "prismatic" else "t") + along)
        entries.append({"joints": name, "dofs": [*dofs, "offset"]})
    if tool and TOOL_JOINT in tree.joints:
        dofs = list(_SIX) if tool is True else list(tool)
        entries.append({"joints": TOOL_JOINT, "dofs": dofs})
    return entries


def serial_mechanism(
    spec: str | Path,
    flange: str | None = None,
    *,
    lock: Mapping[str, float] | None = None,
    base: bool = True,
    T_instrument_base: pin.SE3 | None = None,
    T_flange_tool: pin.SE3 | None = None,
    measured: str | Sequence[str] | None = None,
    root: str | None = None,
) -> Mechanism:
    """Load a serial robot with base and tool frames (and locked joints).

    Args:
        spec: anything :func:`pincal.load_mechanism` accepts (bundled model, URDF path,
            example-robot-data name such as ``"ur10"`` or ``"panda"``, a local sidecar
            with ``robot:``, whose ``lock`` applies too); an example-robot-data robot
            takes its SRDF home but keeps its URDF ranges for sampling (the scripts'
            seeded draws are unchanged).
        flange: link carrying the tool frame; the measured frame becomes ``tool``.
            None: no tool frame, the sidecar's (or the automatically chosen) measured frame.
        lock: movable joints to make fixed, ``{name: value}`` (e.g. Panda fingers).
        base: add the ``base_frame`` joint (instrument → robot root).
        T_instrument_base: initial placement of the robot base in the instrument frame,
            the ``base_frame`` joint origin [m] (default identity).
        T_flange_tool: initial placement of the tool in the flange frame, the
            ``tool_frame`` joint origin [m] (default identity).
        measured: measured components (``"pose"``, ``"position"`` or a list);
            default the sidecar's, else pose.
        root: the link the chain starts from (the instrument is fixed to it), if not the
            URDF's root: the tree is re-rooted there (:func:`reroot_urdf`; joints keep
            their names and values, ``base_frame`` joins the instrument to ``root``).

    The model's sidecar (if any) is kept, with ``measured_frame`` and ``measured``
    overridden and two presets added: ``chain`` (:func:`chain_preset`) and
    ``base_tool`` (only the 6 + 6 frame parameters).
    """
    named = resolve_named(spec)
    urdf_path, sidecar = named.urdf, dict(named.sidecar)
    lock = lock_values_at_home({**named.lock, **(lock or {})}, sidecar.get("home"))
    xml = read_text(urdf_path, "URDF", error=ModelFileError)
    if lock:
        xml = lock_joints(xml, lock)
        gone = {n for n, j in UrdfTree(xml).joints.items() if not j.movable}
        if isinstance(sidecar.get("home"), Mapping):
            sidecar["home"] = {k: v for k, v in sidecar["home"].items() if k not in gone}
    if root is not None:
        xml = reroot_urdf(xml, root)
    xml = wrap_base_tool(xml, flange, T_instrument_base, T_flange_tool, base=base)
    if flange is not None:
        sidecar["measured_frame"] = TOOL_LINK
    if measured is not None:
        sidecar["measured"] = measured if isinstance(measured, str) else list(measured)
    if lock and "name_mot" in sidecar:
        sidecar["name_mot"] = [n for n in sidecar["name_mot"] if n not in lock]
    mech = Mechanism(xml, sidecar, name=urdf_path.stem, source=urdf_path)
    presets = dict(sidecar.get("presets") or {})
    tool_dofs: bool | list[str] = True
    if mech.measured_components == ("x", "y", "z"):
        tool_dofs = ["tx", "ty", "tz"]  # a point: its orientation is not observable
    presets["chain"] = chain_preset(mech, tool=tool_dofs)
    presets["base_tool"] = [e for e in presets["chain"] if e["joints"] in (BASE_JOINT, TOOL_JOINT)]
    sidecar["presets"] = presets
    return Mechanism(xml, sidecar, name=urdf_path.stem, source=urdf_path)


def with_joint_origin(mech: Mechanism, joint: str, T_parent_child: pin.SE3) -> Mechanism:
    """A new mechanism with one URDF joint origin replaced (input unchanged)."""
    return mech.with_joint_origins({joint: T_parent_child})
