"""Minimal URDF tree: joint origins, axes, topology, and origin rewriting.

The URDF text is the source of a mechanism's geometry and what a calibration exports.
Parameters move joint origins in the tree (:meth:`UrdfTree.moved`) and in a copy of the
Pinocchio model (:mod:`pincal.model._placements`); the text with the moved origins is
written only when asked for (:meth:`UrdfTree.text`), and parses to the same model.
"""

from __future__ import annotations

import copy
import dataclasses
import os
import re
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pincal._limits import Limits, active_limits
from pincal.errors import InputLimitError, ModelFileError, UnknownNameError, clip
from pincal.model.files._urdf_check import (
    JOINT_TYPES,
    check_joint_element,
    check_robot_element,
)

__all__ = ["MOVABLE_TYPES", "UrdfJoint", "UrdfTree", "se3_from_xyz_rpy"]

MOVABLE_TYPES = ("revolute", "continuous", "prismatic")

_LINK_TAG = re.compile(r"<link[\s/>]")


@dataclass(frozen=True)
class UrdfJoint:
    """One URDF joint.

    Attributes:
        name: joint name.
        type: URDF type (revolute, continuous, prismatic, fixed, floating, planar).
        parent, child: link names.
        origin: placement of the joint frame in the parent link frame.
        axis: (3,) unit axis in the joint frame (zeros for fixed/floating).
    """

    name: str
    type: str
    parent: str
    child: str
    origin: pin.SE3
    axis: np.ndarray

    @property
    def movable(self) -> bool:
        """True for a joint that moves (revolute, continuous, prismatic…)."""
        return self.type in MOVABLE_TYPES

    def offset_twist(self) -> np.ndarray:
        """(6,) twist along the joint motion: ``[axis; 0]`` prismatic, ``[0; axis]`` revolute."""
        if self.type == "prismatic":
            return np.concatenate([self.axis, np.zeros(3)])
        if self.type in ("revolute", "continuous"):
            return np.concatenate([np.zeros(3), self.axis])
        raise ModelFileError(f"joint {self.name!r} ({self.type}) has no offset")


def _floats(text: str | None, n: int, default: float, where: str) -> np.ndarray:
    if text is None:
        return np.full(n, default)
    try:
        values = np.array([float(s) for s in text.split()])
    except ValueError as exc:
        raise ModelFileError(f"{where}: cannot read numbers from {text!r}") from exc
    if values.shape != (n,) or not np.all(np.isfinite(values)):
        raise ModelFileError(f"{where}: expected {n} finite numbers, got {text!r}")
    return values


def se3_from_xyz_rpy(xyz: np.ndarray, rpy: np.ndarray) -> pin.SE3:
    """The placement of a URDF ``<origin xyz rpy>`` [m, rad]."""
    return pin.SE3(pin.rpy.rpyToMatrix(*rpy), np.asarray(xyz, dtype=float))


class UrdfTree:
    """Parsed URDF: joints by name, link topology, and origin rewriting.

    The text is checked before anything is built (:mod:`pincal.model.files._urdf_check`):
    names, joint attributes and numbers (the message names the joint and attribute),
    and the size limits of :class:`~pincal.model.Limits` (links, degrees of
    freedom, depth). Building the tree is linear in the number of links.

    Args:
        xml: URDF text.
        limits: size limits (default: the ones in force, :func:`pincal.model.active_limits`).
        source: the file the text comes from, named in the messages.

    Raises:
        ModelFileError: malformed XML, a missing or invalid attribute, not one tree.
        InputLimitError: more links, degrees of freedom or depth than the limits.
        UnknownNameError: a joint names a link that does not exist.
    """

    def __init__(
        self, xml: str, limits: Limits | None = None, source: str | os.PathLike | None = None
    ):
        try:
            self._load(xml, limits or active_limits())
        except (ModelFileError, InputLimitError) as exc:
            if source is None:
                raise
            raise type(exc)(f"{clip(str(source), 200)}: {exc}") from None

    def _load(self, xml: str, limits: Limits) -> None:
        # an upper bound of the link count, before spending time and memory on parsing
        limits.check("links", len(_LINK_TAG.findall(xml)), limits.links, "PINCAL_MAX_LINKS", "URDF")
        try:
            self.root = ET.fromstring(xml)
        except ET.ParseError as exc:
            raise ModelFileError(f"URDF is not well-formed XML: {exc}") from exc
        check_robot_element(self.root)
        self.name = self.root.get("name", "robot")
        where = f"URDF robot '{clip(self.name)}'"
        link_elements = self.root.findall("link")
        limits.check("links", len(link_elements), limits.links, "PINCAL_MAX_LINKS", where)
        self.links = [e.get("name", "") for e in link_elements]
        if not self.links:
            raise ModelFileError("URDF has no <link>")
        link_set: set[str] = set()
        for link in self.links:
            if not link:
                raise ModelFileError("URDF <link> without a name attribute; every link needs one")
            if link in link_set:
                raise ModelFileError(f"URDF link '{clip(link)}' is defined twice")
            link_set.add(link)
        self.joints: dict[str, UrdfJoint] = {}
        self._elements: dict[str, ET.Element] = {}
        parent_joint: dict[str, str] = {}
        dof = 0
        for e in self.root.findall("joint"):
            name, jtype, parent, child = check_joint_element(e)
            if name in self.joints:
                raise ModelFileError(f"URDF joint '{clip(name)}' is defined twice")
            for link in (parent, child):
                if link not in link_set:
                    raise UnknownNameError("link", link, self.links)
            if child in parent_joint:
                raise ModelFileError(f"URDF link '{clip(child)}' has two parent joints")
            dof += JOINT_TYPES[jtype]
            self.joints[name] = self._parse_joint(e)
            self._elements[name] = e
            parent_joint[child] = name
        limits.check("degrees of freedom", dof, limits.dof, "PINCAL_MAX_DOF", where)
        self.parent_joint = parent_joint
        roots = [link for link in self.links if link not in parent_joint]
        if len(roots) != 1:
            raise ModelFileError(f"URDF must form one tree; root links are {clip(roots, 200)}")
        self.root_link = roots[0]
        self.depth = self._check_depth(limits, where)
        self._ancestors: dict[str, tuple[str, ...]] = {}
        #: joint origins moved since ``root`` was written (:meth:`moved`): name → (xyz, rpy)
        self._pending: dict[str, tuple[list[float], list[float]]] = {}

    def _check_depth(self, limits: Limits, where: str) -> int:
        """Depth of the tree (joints from the root to the deepest link), in linear time."""
        children: dict[str, list[str]] = {}
        for joint in self.joints.values():
            children.setdefault(joint.parent, []).append(joint.child)
        depth = {self.root_link: 0}
        stack = [self.root_link]
        while stack:
            link = stack.pop()
            for child in children.get(link, ()):
                depth[child] = depth[link] + 1
                stack.append(child)
        if len(depth) != len(self.links):
            loose = [link for link in self.links if link not in depth]
            raise ModelFileError(
                f"URDF links {clip(loose, 200)} are not connected to the root link "
                f"'{clip(self.root_link)}' (their joints form a loop); a URDF must be one tree"
            )
        deepest = max(depth.values())
        limits.check(
            "joints in its deepest chain", deepest, limits.depth, "PINCAL_MAX_TREE_DEPTH", where
        )
        return deepest

    @staticmethod
    def _parse_joint(e: ET.Element) -> UrdfJoint:
        name = e.get("name")
        jtype = e.get("type")
        where = f"URDF joint {name!r}"
        if not name or not jtype:
            raise ModelFileError("URDF <joint> without name or type")
        parent, child = e.find("parent"), e.find("child")
        if parent is None or child is None:
            raise ModelFileError(f"{where} lacks <parent> or <child>")
        origin = e.find("origin")
        xyz = _floats(origin.get("xyz") if origin is not None else None, 3, 0.0, where)
        rpy = _floats(origin.get("rpy") if origin is not None else None, 3, 0.0, where)
        axis = np.zeros(3)
        if jtype in MOVABLE_TYPES:
            ax = e.find("axis")
            axis = _floats(ax.get("xyz") if ax is not None else "1 0 0", 3, 0.0, where)
            scale = np.max(np.abs(axis))
            if scale < 1e-12:
                raise ModelFileError(
                    f'{where} <axis xyz> is zero; give a direction such as xyz="0 0 1"'
                )
            axis = axis / scale  # first to the unit box, so huge entries cannot overflow
            axis = axis / np.linalg.norm(axis)
        return UrdfJoint(
            name,
            jtype,
            parent.get("link", ""),
            child.get("link", ""),
            se3_from_xyz_rpy(xyz, rpy),
            axis,
        )

    def ancestors(self, link: str) -> tuple[str, ...]:
        """URDF joints on the path from the root to ``link`` (root first)."""
        if link not in self._ancestors:
            if link not in self.parent_joint and link != self.root_link:
                raise UnknownNameError("link", link, self.links)
            chain: list[str] = []
            current = link
            while current in self.parent_joint:
                jname = self.parent_joint[current]
                chain.append(jname)
                current = self.joints[jname].parent
            self._ancestors[link] = tuple(reversed(chain))
        return self._ancestors[link]

    def locked(self, names: list[str]) -> tuple[str, UrdfTree]:
        """The URDF text with the joints ``names`` made ``fixed``, and its parsed tree.

        A locked joint stays at 0: its child hangs at the joint origin. Joints that are
        fixed already are left as they are.

        Raises:
            UnknownNameError: a name the URDF does not have.
            ModelFileError: a joint that is neither fixed nor a one-dof joint (revolute,
                continuous, prismatic).
        """
        if self._pending:
            return self.displaced({})[1].locked(names)
        root = copy.deepcopy(self.root)
        by_name = {str(e.get("name")): e for e in root.findall("joint")}
        joints = dict(self.joints)
        for name in names:
            if name not in by_name:
                raise UnknownNameError("joint", name, list(by_name))
            uj = self.joints[name]
            if uj.type == "fixed":
                continue
            if uj.type not in MOVABLE_TYPES:
                raise ModelFileError(
                    f"sidecar joint_type 'fixed' for {name!r}: only a revolute, continuous or "
                    f"prismatic joint can be locked, got a {uj.type} joint"
                )
            e = by_name[name]
            e.set("type", "fixed")
            for tag in ("axis", "limit", "mimic", "dynamics", "safety_controller"):
                for sub in e.findall(tag):
                    e.remove(sub)
            joints[name] = dataclasses.replace(uj, type="fixed", axis=np.zeros(3))
        ET.indent(root)
        tree = copy.copy(self)
        tree.root, tree.joints, tree._elements = root, joints, by_name
        tree._ancestors = dict(self._ancestors)
        return ET.tostring(root, encoding="unicode"), tree

    def with_origins(self, origins: dict[str, pin.SE3]) -> str:
        """Return the URDF text with the given joint origins replaced (full precision)."""
        return self.displaced(origins)[0]

    def moved(self, origins: Mapping[str, pin.SE3]) -> UrdfTree:
        """This tree with the given joint origins replaced, without writing any text.

        The origins are stored as the text would hold them (xyz and rpy in full
        precision, read back), so that :meth:`text` of the moved tree parses to exactly
        these origins. The text is written only when asked for.

        Raises:
            UnknownNameError: an origin names a joint the URDF does not have.
        """
        joints = dict(self.joints)
        pending = dict(self._pending)
        for name, M in origins.items():
            if name not in joints:
                raise UnknownNameError("joint", name, list(joints))
            pending[name] = xyz, rpy = _xyz_rpy(M)
            origin = se3_from_xyz_rpy(np.array(xyz), np.array(rpy))
            joints[name] = dataclasses.replace(joints[name], origin=origin)
        tree = copy.copy(self)
        tree.joints, tree._pending = joints, pending
        return tree

    def text(self) -> str:
        """The URDF text of this tree (its moved origins written in)."""
        return self.displaced({})[0]

    def displaced(self, origins: dict[str, pin.SE3]) -> tuple[str, UrdfTree]:
        """The URDF text with the given joint origins replaced, and its parsed tree.

        The tree is this one with the new origins, equal to parsing the text (the
        numbers are written in full precision and read back from the same values),
        without parsing and checking the text again.

        Raises:
            UnknownNameError: an origin names a joint the URDF does not have.
        """
        written = dict(self._pending)
        written.update((name, _xyz_rpy(M)) for name, M in origins.items())
        root = copy.deepcopy(self.root)
        by_name = {str(e.get("name")): e for e in root.findall("joint")}
        joints = dict(self.joints)
        for name, (xyz, rpy) in written.items():
            if name not in by_name:
                raise UnknownNameError("joint", name, list(by_name))
            e = by_name[name]
            origin = e.find("origin")
            if origin is None:
                origin = ET.SubElement(e, "origin")
            origin.set("xyz", " ".join(repr(v) for v in xyz))
            origin.set("rpy", " ".join(repr(v) for v in rpy))
            joints[name] = dataclasses.replace(
                joints[name], origin=se3_from_xyz_rpy(np.array(xyz), np.array(rpy))
            )
        ET.indent(root)
        tree = copy.copy(self)
        tree.root, tree.joints, tree._elements, tree._pending = root, joints, by_name, {}
        tree._ancestors = dict(self._ancestors)
        return ET.tostring(root, encoding="unicode"), tree


def _xyz_rpy(M: pin.SE3) -> tuple[list[float], list[float]]:
    """The URDF ``xyz`` [m] and ``rpy`` [rad] of a placement (full-precision floats)."""
    return [float(v) for v in M.translation], [float(v) for v in pin.rpy.matrixToRpy(M.rotation)]
