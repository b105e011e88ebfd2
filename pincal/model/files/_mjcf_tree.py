"""MJCF body tree → URDF links and joints (the frame conventions of MuJoCo).

Used by :mod:`pincal.model.loading._mjcf`; see its docstring and models/README.md ("MJCF") for
the mapping. Angles follow ``<compiler angle eulerseq>``; every body link sits at the
MuJoCo body frame, and URDF joint values equal MuJoCo ``qpos`` entries.
"""

from __future__ import annotations

import logging
import xml.etree.ElementTree as ET
from collections import Counter
from typing import Any

import numpy as np
import pinocchio as pin

from pincal._limits import active_limits
from pincal.errors import ModelFileError, UnknownNameError

__all__ = ["MjcfTree", "euler_xyz", "quat_matrix", "unit", "vec"]

log = logging.getLogger(__name__)

ORIENTATIONS = ("quat", "axisangle", "euler", "xyaxes", "zaxis")
REFUSED = ("include", "replicate", "attach")


def vec(text: str | None, n: int, where: str, default: float = 0.0) -> np.ndarray:
    """(n,) finite numbers from an MJCF attribute (``default`` everywhere when absent)."""
    if text is None:
        return np.full(n, default)
    try:
        v = np.array([float(s) for s in text.split()])
    except ValueError as exc:
        raise ModelFileError(f"MJCF {where}: cannot read numbers from {text!r}") from exc
    if v.shape != (n,) or not np.all(np.isfinite(v)):
        raise ModelFileError(f"MJCF {where}: expected {n} finite numbers, got {text!r}")
    return v


def unit(v: np.ndarray, where: str) -> np.ndarray:
    """``v`` normalised; a zero vector is a :class:`ModelFileError` naming ``where``."""
    norm = float(np.linalg.norm(v))
    if norm < 1e-12:
        raise ModelFileError(f"MJCF {where}: zero-length vector {v.tolist()}")
    return v / norm


def quat_matrix(wxyz: np.ndarray, where: str) -> np.ndarray:
    """Rotation matrix (3, 3) of an MJCF quaternion ``w x y z`` (normalised first)."""
    w, x, y, z = unit(wxyz, where)
    return pin.Quaternion(w, x, y, z).toRotationMatrix()


def euler_xyz(R: np.ndarray) -> list[float]:
    """Angles (a, b, c) with R = Rx(a) Ry(b) Rz(c) (the three revolutes of a ball)."""
    b = float(np.arcsin(np.clip(R[0, 2], -1.0, 1.0)))
    return [float(np.arctan2(-R[1, 2], R[2, 2])), b, float(np.arctan2(-R[0, 1], R[0, 0]))]


def _check_size(root: ET.Element, where: str) -> None:
    """Refuse documents past the model limits before the recursive conversion.

    Raises:
        InputLimitError: more bodies and sites than ``Limits.links``, or bodies,
            frames or defaults nested deeper than ``Limits.depth``.
    """
    limits = active_limits()
    count = sum(1 for e in root.iter() if e.tag in ("body", "site"))
    limits.check("bodies and sites", count, limits.links, "PINCAL_MAX_LINKS", where)
    deepest, stack = 0, [(root, 0)]
    while stack:  # iterative: the document may be deeper than Python's recursion limit
        elem, depth = stack.pop()
        deepest = max(deepest, depth)
        stack.extend((c, depth + (c.tag in ("body", "frame", "default"))) for c in elem)
    limits.check("nested bodies", deepest, limits.depth, "PINCAL_MAX_TREE_DEPTH", where)


class MjcfTree:
    """The compiler settings, default classes and body tree of one MJCF document.

    After :meth:`convert_tree`: ``links``/``joints`` (URDF to write with :meth:`urdf`),
    ``body_world`` (body placements at ``qpos0``), ``site_body``, ``mj_joints`` (MuJoCo
    joint → type and URDF joints, in ``qpos`` order), ``qpos0`` and ``leaves``.
    """

    def __init__(self, root: ET.Element, name: str):
        if root.tag != "mujoco":
            raise ModelFileError(f"MJCF root element is <{root.tag}>, expected <mujoco>")
        for tag in REFUSED:
            if root.find(f".//{tag}") is not None:
                raise ModelFileError(
                    f"MJCF <{tag}> is not supported: expand it into one file "
                    "first (e.g. save the model from MuJoCo with mj_saveLastXML)"
                )
        self.root, self.name = root, root.get("model") or name
        _check_size(root, f"MJCF model {self.name!r}")
        self.degree, self.seq, self.autolimits = True, "xyz", True
        for c in root.findall("compiler"):
            if c.get("coordinate", "local") != "local":
                raise ModelFileError("MJCF compiler coordinate='global' is not supported")
            self.degree = c.get("angle", "degree" if self.degree else "radian") == "degree"
            self.seq = c.get("eulerseq", self.seq)
            self.autolimits = c.get("autolimits", "true" if self.autolimits else "false") == "true"
        if len(self.seq) != 3 or any(ch not in "xyzXYZ" for ch in self.seq):
            raise ModelFileError(f"MJCF eulerseq {self.seq!r}: need 3 letters from xyzXYZ")
        self.defaults: dict[str, dict[str, dict[str, str]]] = {}
        for d in root.findall("default"):
            self._read_default(d, {})
        bodies = [b.get("name") for b in root.iter("body")]
        sites = [s.get("name") for s in root.iter("site") if s.get("name")]
        named = [n for n in bodies + sites if n]
        dup = sorted({n for n, k in Counter(named).items() if k > 1} | ({"world"} & set(named)))
        if dup:
            raise ModelFileError(
                f"MJCF body/site names {dup} are used twice (or are 'world'); "
                "URDF link names must be unique: rename them"
            )
        self.used_links = {"world", *named}
        self.used_joints: set[str] = {
            n for tag in ("joint", "freejoint") for j in root.iter(tag) if (n := j.get("name"))
        }
        self.links: list[str] = ["world"]
        self.joints: list[dict[str, Any]] = []
        self.body_link: dict[str, str] = {"world": "world"}
        self.body_world: dict[str, pin.SE3] = {"world": pin.SE3.Identity()}
        self.site_body: dict[str, str] = {}
        self.mj_joints: dict[str, tuple[str, list[str]]] = {}  # name -> (type, urdf joints)
        self.qpos0: list[float] = []
        self.leaves: list[str] = []
        #: hinge/slide joint → (lower, upper) URDF range [rad, m] and MJCF spring stiffness
        self.ranges: dict[str, tuple[float, float]] = {}
        self.stiffness: dict[str, float] = {}

    # ------------------------------------------------------------------ attributes
    def _read_default(self, elem: ET.Element, parent: dict[str, dict[str, str]]) -> None:
        cls = elem.get("class", "main")
        mine = {tag: dict(attrs) for tag, attrs in parent.items()}
        for child in elem:
            if child.tag != "default":
                mine.setdefault(child.tag, {}).update(child.attrib)
        self.defaults[cls] = mine
        for child in elem.findall("default"):
            self._read_default(child, mine)

    def attrs(self, elem: ET.Element, cls: str, tag: str | None = None) -> dict[str, str]:
        """An element's attributes over its default class's (its own orientation wins)."""
        name = elem.get("class", cls)
        if name not in self.defaults and name != "main":
            raise UnknownNameError("MJCF default class", name, list(self.defaults))
        base = dict(self.defaults.get(name, {}).get(tag or elem.tag, {}))
        if any(k in elem.attrib for k in ORIENTATIONS):
            base = {k: v for k, v in base.items() if k not in ORIENTATIONS}
        return base | dict(elem.attrib)

    def _angle(self, value: float) -> float:
        return float(np.deg2rad(value)) if self.degree else float(value)

    def _pose(self, a: dict[str, str], where: str) -> pin.SE3:
        """Placement from pos + one of quat/axisangle/euler/xyaxes/zaxis (or fromto)."""
        given = [k for k in ORIENTATIONS if k in a]
        if len(given) > 1:
            raise ModelFileError(f"MJCF {where}: give one orientation, got {given}")
        pos, R = vec(a.get("pos"), 3, f"{where} pos"), np.eye(3)
        kind = given[0] if given else None
        if kind == "quat":
            R = quat_matrix(vec(a["quat"], 4, f"{where} quat"), f"{where} quat")
        elif kind == "axisangle":
            v = vec(a["axisangle"], 4, f"{where} axisangle")
            R = pin.exp3(unit(v[:3], f"{where} axisangle") * self._angle(v[3]))
        elif kind == "euler":
            for letter, value in zip(self.seq, vec(a["euler"], 3, f"{where} euler"), strict=True):
                Ri = pin.exp3(np.eye(3)["xyz".index(letter.lower())] * self._angle(value))
                R = R @ Ri if letter.islower() else Ri @ R  # lower: moving axes; upper: fixed
        elif kind == "xyaxes":
            v = vec(a["xyaxes"], 6, f"{where} xyaxes")
            x = unit(v[:3], f"{where} xyaxes")
            y = unit(v[3:] - x * (x @ v[3:]), f"{where} xyaxes")
            R = np.column_stack([x, y, np.cross(x, y)])
        elif kind == "zaxis" or "fromto" in a:
            if kind == "zaxis":
                z = unit(vec(a["zaxis"], 3, f"{where} zaxis"), f"{where} zaxis")
            else:
                ft = vec(a["fromto"], 6, f"{where} fromto")
                pos, z = 0.5 * (ft[:3] + ft[3:]), unit(ft[3:] - ft[:3], f"{where} fromto")
            axis = np.cross([0.0, 0.0, 1.0], z)  # minimal rotation from +Z (pi about x if -Z)
            s = float(np.linalg.norm(axis))
            R = pin.exp3((axis / s if s >= 1e-10 else np.eye(3)[0]) * np.arctan2(s, z[2]))
        return pin.SE3(R, pos)

    # ------------------------------------------------------------------ URDF pieces
    def fresh(self, name: str, used: set[str]) -> str:
        """``name``, or ``name_2``, ``name_3``… when taken; recorded as used."""
        out, k = name, 2
        while out in used:
            out, k = f"{name}_{k}", k + 1
        if out != name:
            log.info("MJCF import: generated name %r taken, using %r", name, out)
        used.add(out)
        return out

    def _add(
        self,
        name: str,
        jtype: str,
        parent: str,
        child: str,
        origin: pin.SE3,
        axis: np.ndarray | None = None,
        limits: tuple[float, float] | None = None,
    ) -> None:
        if child not in self.links:
            self.links.append(child)
        self.joints.append(
            dict(
                name=name,
                type=jtype,
                parent=parent,
                child=child,
                origin=origin,
                axis=axis,
                limits=limits,
            )
        )

    def fixed(self, parent: str, child: str, origin: pin.SE3) -> None:
        """Add a fixed joint placing ``child`` at ``origin`` in ``parent``."""
        self._add(self.fresh(f"{child}_frame", self.used_joints), "fixed", parent, child, origin)

    # ------------------------------------------------------------------ tree
    def convert_tree(self) -> None:
        """Convert the ``<worldbody>`` into links and joints (ModelFileError without a body)."""
        world = self.root.find("worldbody")
        if world is None or world.find(".//body") is None:
            raise ModelFileError("MJCF has no <worldbody> with a <body>")
        self._children(world, "world", pin.SE3.Identity(), "main")

    def _children(self, elem: ET.Element, body: str, prefix: pin.SE3, cls: str) -> None:
        for child in elem:
            if child.tag == "body":
                self._body(child, body, prefix, cls)
            elif child.tag == "frame":
                pose = self._pose(self.attrs(child, cls), "<frame>")
                self._children(child, body, prefix * pose, child.get("childclass", cls))
            elif child.tag == "site" and child.get("name"):
                site = child.get("name", "")
                pose = self._pose(self.attrs(child, cls), f"site {site!r}")
                self.fixed(self.body_link[body], site, prefix * pose)
                self.site_body[site] = body

    def _body(self, elem: ET.Element, parent: str, prefix: pin.SE3, cls: str) -> None:
        name = elem.get("name") or self.fresh(f"body{len(self.body_link)}", self.used_links)
        where = f"body {name!r}"
        cls = elem.get("childclass", cls)
        local = prefix * self._pose(dict(elem.attrib), where)
        self.body_world[name] = self.body_world[parent] * local
        self.body_link[name] = name
        if elem.get("mocap") == "true":
            log.warning("MJCF import: mocap body %r is kept fixed at its file pose", name)
        joints = [j for j in elem if j.tag in ("joint", "freejoint")]
        link, origin, offset = self.body_link[parent], local, np.zeros(3)
        for k, j in enumerate(joints):
            a = self.attrs(j, cls, "joint")
            kind = "free" if j.tag == "freejoint" else a.get("type", "hinge")
            jname = a.get("name") or self.fresh(f"{name}_joint{k}", self.used_joints)
            if kind == "free":
                if parent != "world" or len(joints) > 1:
                    raise ModelFileError(
                        f"MJCF free joint {jname!r}: only alone in a top-level body"
                    )
                self._add(jname, "floating", "world", name, pin.SE3.Identity())
                q = pin.SE3ToXYZQUAT(self.body_world[name])
                self.qpos0 += [*q[:3], q[6], *q[3:6]]  # MuJoCo order: x y z w qx qy qz
                self.mj_joints[jname] = ("free", [jname])
                link, origin = name, None
                break
            pos = vec(a.get("pos"), 3, f"joint {jname!r} pos")
            start = origin * pin.SE3(np.eye(3), pos - offset)
            last = k == len(joints) - 1
            child = name if last and not pos.any() else self.fresh(f"{jname}_link", self.used_links)
            if kind == "ball":
                names = [self.fresh(f"{jname}_{c}", self.used_joints) for c in "xyz"]
                mids = [self.fresh(f"{jname}_link{i}", self.used_links) for i in (1, 2)]
                for i, (jn, ch) in enumerate(zip(names, [*mids, child], strict=True)):
                    self._add(
                        jn,
                        "revolute",
                        link,
                        ch,
                        start if i == 0 else pin.SE3.Identity(),
                        np.eye(3)[i],
                        (-np.pi, np.pi),
                    )
                    link = ch
                self.qpos0 += [1.0, 0.0, 0.0, 0.0]
                self.mj_joints[jname] = ("ball", names)
            elif kind in ("hinge", "slide"):
                axis = unit(vec(a.get("axis", "0 0 1"), 3, f"joint {jname!r} axis"), jname)
                scale = self._angle if kind == "hinge" else float
                ref = scale(float(a.get("ref", "0")))
                limited = a.get("limited", "auto")
                if limited == "true" or (limited == "auto" and self.autolimits and "range" in a):
                    lo, hi = (scale(v) for v in vec(a.get("range"), 2, f"joint {jname!r} range"))
                else:
                    lo, hi = (-np.pi, np.pi) if kind == "hinge" else (-1.0, 1.0)
                    log.info(
                        "MJCF import: joint %r has no range; URDF limits [%g, %g]", jname, lo, hi
                    )
                shift = pin.exp6(
                    pin.Motion(
                        *(
                            (-ref * axis, np.zeros(3))
                            if kind == "slide"
                            else (np.zeros(3), -ref * axis)
                        )
                    )
                )
                self._add(
                    jname,
                    "revolute" if kind == "hinge" else "prismatic",
                    link,
                    child,
                    start * shift,
                    axis,
                    (lo, hi),
                )
                self.qpos0.append(ref)
                self.mj_joints[jname] = (kind, [jname])
                self.ranges[jname] = (float(lo), float(hi))
                k_spring = float(vec(a.get("stiffness"), 1, f"joint {jname!r} stiffness")[0])
                if k_spring > 0:
                    self.stiffness[jname] = k_spring
                link = child
            else:
                raise ModelFileError(
                    f"MJCF joint {jname!r} has unknown type {kind!r}; valid: "
                    "hinge, slide, ball, free"
                )
            origin, offset = pin.SE3.Identity(), pos
        if origin is not None and (not joints or offset.any()):
            self.fixed(link, name, origin * pin.SE3(np.eye(3), -offset))
        if elem.find("body") is None and elem.find("frame/body") is None:
            self.leaves.append(name)
        self._children(elem, name, pin.SE3.Identity(), cls)

    def urdf(self) -> str:
        """The converted tree as URDF text."""
        robot = ET.Element("robot", name=self.name)
        for link in self.links:
            ET.SubElement(robot, "link", name=link)
        for j in self.joints:
            e = ET.SubElement(robot, "joint", name=j["name"], type=j["type"])
            ET.SubElement(e, "parent", link=j["parent"])
            ET.SubElement(e, "child", link=j["child"])
            M = j["origin"]
            ET.SubElement(
                e,
                "origin",
                xyz=" ".join(repr(float(v)) for v in M.translation),
                rpy=" ".join(repr(float(v)) for v in pin.rpy.matrixToRpy(M.rotation)),
            )
            if j["axis"] is not None:
                ET.SubElement(e, "axis", xyz=" ".join(repr(float(v)) for v in j["axis"]))
                lo, hi = j["limits"]
                ET.SubElement(
                    e,
                    "limit",
                    lower=repr(float(lo)),
                    upper=repr(float(hi)),
                    effort="0",
                    velocity="0",
                )
        ET.indent(robot)
        return ET.tostring(robot, encoding="unicode") + "\n"
