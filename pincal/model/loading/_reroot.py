"""A URDF tree re-rooted at another link: a chain measured from a link other than the root.

A humanoid standing on one sole, a mobile manipulator whose torso is fixed to the
instrument, a chain measured from the hand back to the body: the measured chain starts
at a link other than the URDF root. :func:`reroot_urdf` rewrites the URDF so that the
chosen link is the root; every link keeps its own frame (inertias, visuals and the
other joints are unchanged) and every movable joint keeps its name, type, limits and
the sign of its value:

* a joint on the path from the old root to the new one, ``P --(O, axis a)--> C``
  (``T_P_C(q) = O · exp(q a)``), is turned around as ``C --(identity, axis −a)-->
  <name>_reversed --(fixed, O⁻¹)--> P``: ``T_C_P(q) = exp(−q a) · O⁻¹``, the exact
  inverse for every ``q``. The joint values in a data file apply unchanged.
* a fixed joint on that path becomes ``C --(fixed, O⁻¹)--> P``.

The geometry of a turned joint sits in the fixed joint after it, which is exactly
redundant with the next movable joint's origin (or the tool frame): the
:func:`pincal.model.chain_preset` of the re-rooted chain (every movable joint's origin)
spans the same errors as the original joints' origins — a placement error ``O·exp(δ)``
of the original tree is ``O⁻¹·exp(−Ad(O)δ)`` there.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import pinocchio as pin

from pincal.errors import ModelFileError, UnknownNameError
from pincal.model.files import MOVABLE_TYPES, UrdfTree

__all__ = ["REVERSED_SUFFIX", "chain_joints", "reroot_urdf"]

#: the link between a turned joint and its old parent: ``<joint name>_reversed``
REVERSED_SUFFIX = "_reversed"


def _origin(M: pin.SE3) -> dict[str, str]:
    rpy = pin.rpy.matrixToRpy(M.rotation)
    return {
        "xyz": " ".join(repr(float(v)) for v in M.translation),
        "rpy": " ".join(repr(float(v)) for v in rpy),
    }


def chain_joints(tree: UrdfTree, root: str, link: str) -> tuple[str, ...]:
    """The URDF joints on the path between links ``root`` and ``link`` (any direction).

    Raises:
        UnknownNameError: either is not a link of the tree.
    """
    for name in (root, link):
        if name not in tree.links:
            raise UnknownNameError("link", name, tree.links)
    up, down = tree.ancestors(root), tree.ancestors(link)
    common = 0
    while common < min(len(up), len(down)) and up[common] == down[common]:
        common += 1
    return (*reversed(up[common:]), *down[common:])


def reroot_urdf(urdf_xml: str, link: str) -> str:
    """URDF text of the same robot with ``link`` as its root (see the module's text).

    Args:
        urdf_xml: the URDF.
        link: the new root link (the URDF's root: the text is returned unchanged).

    Raises:
        UnknownNameError: ``link`` is not a link of the URDF.
        ModelFileError: a floating or planar joint lies between the two roots (only
            revolute, continuous, prismatic and fixed joints can be turned around), or
            a ``<name>_reversed`` link exists already.
    """
    tree = UrdfTree(urdf_xml)
    if link not in tree.links:
        raise UnknownNameError("link", link, tree.links)
    if link == tree.root_link:
        return urdf_xml
    path = tree.ancestors(link)
    root = ET.fromstring(urdf_xml)
    elements = {str(e.get("name")): e for e in root.findall("joint")}
    for name in path:
        uj = tree.joints[name]
        if uj.type not in (*MOVABLE_TYPES, "fixed"):
            raise ModelFileError(
                f"cannot re-root at {link!r}: joint {name!r} between it and the URDF root "
                f"{tree.root_link!r} is {uj.type}; only revolute, continuous, prismatic "
                "and fixed joints can be turned around (choose a root on the same side)"
            )
        e = elements[name]
        e.find("parent").set("link", uj.child)  # type: ignore[union-attr]
        origin = e.find("origin")
        if origin is None:
            origin = ET.SubElement(e, "origin")
        if uj.type == "fixed":
            e.find("child").set("link", uj.parent)  # type: ignore[union-attr]
            origin.attrib.update(_origin(uj.origin.inverse()))
            continue
        between = f"{name}{REVERSED_SUFFIX}"
        if between in tree.links or f"{between}_origin" in tree.joints:
            raise ModelFileError(f"cannot re-root at {link!r}: the URDF has a link {between!r} "
                                 f"or a joint {between + '_origin'!r}")  # fmt: skip
        e.find("child").set("link", between)  # type: ignore[union-attr]
        origin.attrib.update(_origin(pin.SE3.Identity()))
        axis = e.find("axis")
        if axis is None:
            axis = ET.SubElement(e, "axis")
        axis.set("xyz", " ".join(repr(float(-v)) for v in uj.axis))
        root.append(ET.Element("link", {"name": between}))
        fixed = ET.SubElement(root, "joint", {"name": f"{between}_origin", "type": "fixed"})
        ET.SubElement(fixed, "parent", {"link": between})
        ET.SubElement(fixed, "child", {"link": uj.parent})
        ET.SubElement(fixed, "origin", _origin(uj.origin.inverse()))
    # the new root link first: Pinocchio's parser and wrap_base_tool read it from there
    first = next(e for e in root.findall("link") if e.get("name") == link)
    root.remove(first)
    root.insert(0, first)
    return ET.tostring(root, encoding="unicode")
