"""Minimal URDF tree: joint origins, axes, topology, and origin rewriting.

pincal treats the URDF text as the source of truth of a mechanism's geometry:
parameters displace joint origins in the XML, and the Pinocchio model is rebuilt
from the text. This keeps the exported URDF exactly the identified model.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pincal.errors import ModelFileError, UnknownNameError

__all__ = ["MOVABLE_TYPES", "UrdfJoint", "UrdfTree", "se3_from_xyz_rpy"]

MOVABLE_TYPES = ("revolute", "continuous", "prismatic")


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
    return pin.SE3(pin.rpy.rpyToMatrix(*rpy), np.asarray(xyz, dtype=float))


class UrdfTree:
    """Parsed URDF: joints by name, link topology, and origin rewriting."""

    def __init__(self, xml: str):
        try:
            self.root = ET.fromstring(xml)
        except ET.ParseError as exc:
            raise ModelFileError(f"URDF is not well-formed XML: {exc}") from exc
        if self.root.tag != "robot":
            raise ModelFileError(f"URDF root element is <{self.root.tag}>, expected <robot>")
        self.name = self.root.get("name", "robot")
        self.links = [e.get("name", "") for e in self.root.findall("link")]
        if not self.links:
            raise ModelFileError("URDF has no <link>")
        self.joints: dict[str, UrdfJoint] = {}
        self._elements: dict[str, ET.Element] = {}
        parent_joint: dict[str, str] = {}
        for e in self.root.findall("joint"):
            joint = self._parse_joint(e)
            if joint.name in self.joints:
                raise ModelFileError(f"URDF joint {joint.name!r} is defined twice")
            for link in (joint.parent, joint.child):
                if link not in self.links:
                    raise UnknownNameError("link", link, self.links)
            if joint.child in parent_joint:
                raise ModelFileError(f"URDF link {joint.child!r} has two parent joints")
            self.joints[joint.name] = joint
            self._elements[joint.name] = e
            parent_joint[joint.child] = joint.name
        self.parent_joint = parent_joint
        roots = [link for link in self.links if link not in parent_joint]
        if len(roots) != 1:
            raise ModelFileError(f"URDF must form one tree; root links are {roots}")
        self.root_link = roots[0]
        self._ancestors: dict[str, tuple[str, ...]] = {}

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
                raise ModelFileError(f"{where} has a zero axis")
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
            if link not in self.links:
                raise UnknownNameError("link", link, self.links)
            chain: list[str] = []
            current = link
            while current in self.parent_joint:
                jname = self.parent_joint[current]
                chain.append(jname)
                current = self.joints[jname].parent
            self._ancestors[link] = tuple(reversed(chain))
        return self._ancestors[link]

    def with_origins(self, origins: dict[str, pin.SE3]) -> str:
        """Return the URDF text with the given joint origins replaced (full precision)."""
        root = ET.fromstring(ET.tostring(self.root))
        by_name = {str(e.get("name")): e for e in root.findall("joint")}
        for name, M in origins.items():
            if name not in by_name:
                raise UnknownNameError("joint", name, list(by_name))
            e = by_name[name]
            origin = e.find("origin")
            if origin is None:
                origin = ET.SubElement(e, "origin")
            rpy = pin.rpy.matrixToRpy(M.rotation)
            origin.set("xyz", " ".join(repr(float(v)) for v in M.translation))
            origin.set("rpy", " ".join(repr(float(v)) for v in rpy))
        ET.indent(root)
        return ET.tostring(root, encoding="unicode")
