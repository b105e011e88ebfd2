"""MJCF (MuJoCo XML) import: converted to URDF text + sidecar, then a :class:`Mechanism`.

pincal's parameters displace URDF joint origins and export writes URDF, so an MJCF file
is translated once into the URDF route (models/README.md, section "MJCF"):

* every ``<body>`` (any number under ``<worldbody>``, nested ``<frame>`` s honoured)
  becomes a URDF link of the same name placed at the MuJoCo body frame; a body without
  joints hangs on a ``fixed`` joint ``<body>_frame``;
* ``hinge``/``slide`` joints become ``revolute``/``prismatic`` joints of the same name
  with URDF value = MuJoCo ``qpos`` (``ref`` and off-body ``pos`` are folded into the
  origins; an off-origin joint gets an extra link ``<joint>_link``); ``ball`` becomes
  three revolutes ``<joint>_x``, ``_y``, ``_z`` about the body axes at the joint centre
  (URDF has no spherical joint; a 3d closure would lose the body's rotation); ``free``
  becomes a ``floating`` joint;
* named ``<site>`` s become fixed child links; ``<equality><connect>`` becomes a ``3d``
  closure between the links ``<eq>_1`` (anchor on body1) and ``<eq>_2`` (the same point
  in body2 at ``qpos0``), or between the two sites; ``<weld>`` becomes a ``6d`` closure
  (``relpose``, else the ``qpos0`` relative pose); equality names are kept in the
  sidecar key ``mjcf_equality``;
* actuators with ``joint=`` give ``name_mot`` (names in ``mjcf_actuators``); the
  ``home`` guess is the keyframe ``home`` (else the first keyframe, else ``qpos0``).

Joint/tendon/flex equalities and ``<include>`` are refused (:class:`ModelFileError`);
actuators on tendons, sites or bodies are skipped with a logged warning. Geometry,
inertia, tendons, sensors and contacts do not affect kinematics and are ignored.
"""

from __future__ import annotations

import logging
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from pincal.errors import ModelFileError, UnknownNameError

__all__ = ["load_mjcf", "mjcf_to_urdf"]

log = logging.getLogger(__name__)

ACTUATOR_TAGS = ("motor", "position", "velocity", "general", "intvelocity", "damper",
                 "cylinder", "muscle", "adhesion")
ORIENTATIONS = ("quat", "axisangle", "euler", "xyaxes", "zaxis")
REFUSED = ("include", "replicate", "attach")


def _vec(text: str | None, n: int, where: str, default: float = 0.0) -> np.ndarray:
    if text is None:
        return np.full(n, default)
    try:
        v = np.array([float(s) for s in text.split()])
    except ValueError as exc:
        raise ModelFileError(f"MJCF {where}: cannot read numbers from {text!r}") from exc
    if v.shape != (n,) or not np.all(np.isfinite(v)):
        raise ModelFileError(f"MJCF {where}: expected {n} finite numbers, got {text!r}")
    return v


def _unit(v: np.ndarray, where: str) -> np.ndarray:
    norm = float(np.linalg.norm(v))
    if norm < 1e-12:
        raise ModelFileError(f"MJCF {where}: zero-length vector {v.tolist()}")
    return v / norm


def _quat_matrix(wxyz: np.ndarray, where: str) -> np.ndarray:
    w, x, y, z = _unit(wxyz, where)
    return pin.Quaternion(w, x, y, z).toRotationMatrix()


def _euler_xyz(R: np.ndarray) -> list[float]:
    """Angles (a, b, c) with R = Rx(a) Ry(b) Rz(c) (the three revolutes of a ball)."""
    b = float(np.arcsin(np.clip(R[0, 2], -1.0, 1.0)))
    return [float(np.arctan2(-R[1, 2], R[2, 2])), b, float(np.arctan2(-R[0, 1], R[0, 0]))]


class _Converter:
    """One pass over an MJCF tree; fills URDF links/joints and the sidecar."""

    def __init__(self, root: ET.Element, name: str):
        if root.tag != "mujoco":
            raise ModelFileError(f"MJCF root element is <{root.tag}>, expected <mujoco>")
        for tag in REFUSED:
            if root.find(f".//{tag}") is not None:
                raise ModelFileError(f"MJCF <{tag}> is not supported: expand it into one file "
                                     "first (e.g. save the model from MuJoCo with mj_saveLastXML)")
        self.root, self.name = root, root.get("model") or name
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
        dup = sorted({n for n in named if named.count(n) > 1} | ({"world"} & set(named)))
        if dup:
            raise ModelFileError(f"MJCF body/site names {dup} are used twice (or are 'world'); "
                                 "URDF link names must be unique: rename them")
        self.used_links = {"world", *named}
        self.used_joints = {j.get("name") for j in root.iter("joint") if j.get("name")}
        self.used_joints |= {j.get("name") for j in root.iter("freejoint") if j.get("name")}
        self.links: list[str] = ["world"]
        self.joints: list[dict[str, Any]] = []
        self.body_link: dict[str, str] = {"world": "world"}
        self.body_world: dict[str, pin.SE3] = {"world": pin.SE3.Identity()}
        self.site_body: dict[str, str] = {}
        self.mj_joints: dict[str, tuple[str, list[str]]] = {}  # name -> (type, urdf joints)
        self.qpos0: list[float] = []
        self.leaves: list[str] = []

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

    def _attrs(self, elem: ET.Element, cls: str, tag: str | None = None) -> dict[str, str]:
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
        pos, R = _vec(a.get("pos"), 3, f"{where} pos"), np.eye(3)
        kind = given[0] if given else None
        if kind == "quat":
            R = _quat_matrix(_vec(a["quat"], 4, f"{where} quat"), f"{where} quat")
        elif kind == "axisangle":
            v = _vec(a["axisangle"], 4, f"{where} axisangle")
            R = pin.exp3(_unit(v[:3], f"{where} axisangle") * self._angle(v[3]))
        elif kind == "euler":
            for axis, value in zip(self.seq, _vec(a["euler"], 3, f"{where} euler"), strict=True):
                Ri = pin.exp3(np.eye(3)["xyz".index(axis.lower())] * self._angle(value))
                R = R @ Ri if axis.islower() else Ri @ R
        elif kind == "xyaxes":
            v = _vec(a["xyaxes"], 6, f"{where} xyaxes")
            x = _unit(v[:3], f"{where} xyaxes")
            y = _unit(v[3:] - x * (x @ v[3:]), f"{where} xyaxes")
            R = np.column_stack([x, y, np.cross(x, y)])
        elif kind == "zaxis" or "fromto" in a:
            if kind == "zaxis":
                z = _unit(_vec(a["zaxis"], 3, f"{where} zaxis"), f"{where} zaxis")
            else:
                ft = _vec(a["fromto"], 6, f"{where} fromto")
                pos, z = 0.5 * (ft[:3] + ft[3:]), _unit(ft[3:] - ft[:3], f"{where} fromto")
            axis = np.cross([0.0, 0.0, 1.0], z)  # minimal rotation from +Z (pi about x if -Z)
            s = float(np.linalg.norm(axis))
            R = pin.exp3((axis / s if s >= 1e-10 else np.eye(3)[0]) * np.arctan2(s, z[2]))
        return pin.SE3(R, pos)

    # ------------------------------------------------------------------ URDF pieces
    def _fresh(self, name: str, used: set[str]) -> str:
        out, k = name, 2
        while out in used:
            out, k = f"{name}_{k}", k + 1
        if out != name:
            log.info("MJCF import: generated name %r taken, using %r", name, out)
        used.add(out)
        return out

    def _add(self, name: str, jtype: str, parent: str, child: str, origin: pin.SE3,
             axis: np.ndarray | None = None, limits: tuple[float, float] | None = None) -> None:
        if child not in self.links:
            self.links.append(child)
        self.joints.append(dict(name=name, type=jtype, parent=parent, child=child,
                                origin=origin, axis=axis, limits=limits))

    def _fixed(self, parent: str, child: str, origin: pin.SE3) -> None:
        self._add(self._fresh(f"{child}_frame", self.used_joints), "fixed", parent, child, origin)

    # ------------------------------------------------------------------ tree
    def convert_tree(self) -> None:
        world = self.root.find("worldbody")
        if world is None or world.find(".//body") is None:
            raise ModelFileError("MJCF has no <worldbody> with a <body>")
        self._children(world, "world", pin.SE3.Identity(), "main")

    def _children(self, elem: ET.Element, body: str, prefix: pin.SE3, cls: str) -> None:
        for child in elem:
            if child.tag == "body":
                self._body(child, body, prefix, cls)
            elif child.tag == "frame":
                pose = self._pose(self._attrs(child, cls), "<frame>")
                self._children(child, body, prefix * pose, child.get("childclass", cls))
            elif child.tag == "site" and child.get("name"):
                site = child.get("name", "")
                pose = self._pose(self._attrs(child, cls), f"site {site!r}")
                self._fixed(self.body_link[body], site, prefix * pose)
                self.site_body[site] = body

    def _body(self, elem: ET.Element, parent: str, prefix: pin.SE3, cls: str) -> None:
        name = elem.get("name") or self._fresh(f"body{len(self.body_link)}", self.used_links)
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
            a = self._attrs(j, cls, "joint")
            kind = "free" if j.tag == "freejoint" else a.get("type", "hinge")
            jname = a.get("name") or self._fresh(f"{name}_joint{k}", self.used_joints)
            if kind == "free":
                if parent != "world" or len(joints) > 1:
                    raise ModelFileError(f"MJCF free joint {jname!r}: only alone in a top-level "
                                         "body")
                self._add(jname, "floating", "world", name, pin.SE3.Identity())
                q = pin.SE3ToXYZQUAT(self.body_world[name])
                self.qpos0 += [*q[:3], q[6], *q[3:6]]  # MuJoCo order: x y z w qx qy qz
                self.mj_joints[jname] = ("free", [jname])
                link, origin = name, None
                break
            pos = _vec(a.get("pos"), 3, f"joint {jname!r} pos")
            start = origin * pin.SE3(np.eye(3), pos - offset)
            last = k == len(joints) - 1
            child = name if last and not pos.any() else self._fresh(f"{jname}_link",
                                                                   self.used_links)
            if kind == "ball":
                names = [self._fresh(f"{jname}_{c}", self.used_joints) for c in "xyz"]
                mids = [self._fresh(f"{jname}_link{i}", self.used_links) for i in (1, 2)]
                for i, (jn, ch) in enumerate(zip(names, [*mids, child], strict=True)):
                    self._add(jn, "revolute", link, ch, start if i == 0 else pin.SE3.Identity(),
                              np.eye(3)[i], (-np.pi, np.pi))
                    link = ch
                self.qpos0 += [1.0, 0.0, 0.0, 0.0]
                self.mj_joints[jname] = ("ball", names)
            elif kind in ("hinge", "slide"):
                axis = _unit(_vec(a.get("axis", "0 0 1"), 3, f"joint {jname!r} axis"), jname)
                scale = self._angle if kind == "hinge" else float
                ref = scale(float(a.get("ref", "0")))
                limited = a.get("limited", "auto")
                if limited == "true" or (limited == "auto" and self.autolimits and "range" in a):
                    lo, hi = (scale(v) for v in _vec(a.get("range"), 2, f"joint {jname!r} range"))
                else:
                    lo, hi = (-np.pi, np.pi) if kind == "hinge" else (-1.0, 1.0)
                    log.info("MJCF import: joint %r has no range; URDF limits [%g, %g]",
                             jname, lo, hi)
                shift = pin.exp6(pin.Motion(*((-ref * axis, np.zeros(3)) if kind == "slide"
                                              else (np.zeros(3), -ref * axis))))
                self._add(jname, "revolute" if kind == "hinge" else "prismatic", link, child,
                          start * shift, axis, (lo, hi))
                self.qpos0.append(ref)
                self.mj_joints[jname] = (kind, [jname])
                link = child
            else:
                raise ModelFileError(f"MJCF joint {jname!r} has unknown type {kind!r}; valid: "
                                     "hinge, slide, ball, free")
            origin, offset = pin.SE3.Identity(), pos
        if origin is not None and (not joints or offset.any()):
            self._fixed(link, name, origin * pin.SE3(np.eye(3), -offset))
        if elem.find("body") is None and elem.find("frame/body") is None:
            self.leaves.append(name)
        self._children(elem, name, pin.SE3.Identity(), cls)

    # ------------------------------------------------------------------ constraints
    def _section(self, tag: str) -> list[ET.Element]:
        return [e for section in self.root.findall(tag) for e in section]

    def _body_of(self, name: str | None) -> str:
        name = name or "world"
        if name not in self.body_link:
            raise UnknownNameError("MJCF body", name, list(self.body_link))
        return name

    def _site(self, name: str) -> str:
        if name not in self.site_body:
            raise UnknownNameError("MJCF site", name, list(self.site_body))
        return name

    def closures(self) -> tuple[list[list[str]], list[str], list[str]]:
        pairs: list[list[str]] = []
        kinds: list[str] = []
        names: list[str] = []
        for k, e in enumerate(self._section("equality")):
            a = self._attrs(e, "main", "equality")
            if e.tag not in ("connect", "weld"):
                raise ModelFileError(
                    f"MJCF <equality><{e.tag}> is not supported (it couples joint or tendon "
                    "values, not frames); only connect (3d) and weld (6d) closures are")
            name = a.get("name") or f"{e.tag}{k}"
            if a.get("active", "true") == "false":
                log.warning("MJCF import: inactive equality %r skipped", name)
                continue
            if "site1" in a or "site2" in a:
                pair = [self._site(a.get("site1", "")), self._site(a.get("site2", ""))]
            else:
                b1, b2 = self._body_of(a.get("body1")), self._body_of(a.get("body2"))
                X1, X2 = self.body_world[b1], self.body_world[b2]
                if e.tag == "connect":
                    anchor = _vec(a.get("anchor"), 3, f"connect {name!r} anchor")
                    Ta = pin.SE3(np.eye(3), anchor)
                    Tb = pin.SE3(np.eye(3), X2.actInv(X1.act(anchor)))
                else:
                    Tb = pin.SE3(np.eye(3), _vec(a.get("anchor"), 3, f"weld {name!r} anchor"))
                    rel = _vec(a.get("relpose", "0 1 0 0 0 0 0"), 7, f"weld {name!r} relpose")
                    Ta = (X1.actInv(X2) * Tb if not rel[3:].any()
                          else pin.SE3(_quat_matrix(rel[3:], f"weld {name!r}"), rel[:3]))
                pair = [self._fresh(f"{name}_1", self.used_links),
                        self._fresh(f"{name}_2", self.used_links)]
                self._fixed(self.body_link[b1], pair[0], Ta)
                self._fixed(self.body_link[b2], pair[1], Tb)
            pairs.append(pair)
            kinds.append("3d" if e.tag == "connect" else "6d")
            names.append(name)
        return pairs, kinds, names

    def actuators(self) -> dict[str, str]:
        out: dict[str, str] = {}
        for k, e in enumerate(self._section("actuator")):
            a = self._attrs(e, "main")
            name = a.get("name") or f"{e.tag}{k}"
            target = a.get("joint") or a.get("jointinparent")
            if e.tag not in ACTUATOR_TAGS or target is None:
                log.warning("MJCF import: actuator %r (<%s>) has no joint transmission and is "
                            "skipped; declare the actuated joints with load_mjcf(actuated=...)",
                            name, e.tag)
                continue
            if target not in self.mj_joints:
                raise UnknownNameError("MJCF joint", target, list(self.mj_joints))
            if self.mj_joints[target][0] not in ("hinge", "slide"):
                raise ModelFileError(f"MJCF actuator {name!r} drives the "
                                     f"{self.mj_joints[target][0]} joint {target!r}; pincal "
                                     "actuates 1-dof (hinge/slide) joints only")
            out[name] = target
        return out

    def home(self, keyframe: str | None) -> dict[str, Any]:
        keys = self.root.findall("keyframe/key")
        named = [k for k in keys if k.get("name") == (keyframe or "home")]
        if keyframe is not None and not named:
            raise UnknownNameError("MJCF keyframe", keyframe, [k.get("name", "") for k in keys])
        key = named[0] if named else (keys[0] if keys else None)
        qpos = np.array(self.qpos0)
        if key is not None and key.get("qpos") is not None:
            qpos = _vec(key.get("qpos"), qpos.size, f"keyframe {key.get('name', '')!r} qpos")
        home: dict[str, Any] = {}
        i = 0
        for jname, (kind, urdf) in self.mj_joints.items():
            if kind in ("hinge", "slide"):
                home[jname], i = float(qpos[i]), i + 1
            elif kind == "ball":
                angles = _euler_xyz(_quat_matrix(qpos[i : i + 4], f"ball {jname!r} qpos"))
                home.update(zip(urdf, angles, strict=True))
                i += 4
            else:
                w = qpos[i + 3 : i + 7]
                q = pin.Quaternion(*_unit(w, f"free {jname!r} qpos")).coeffs()  # x y z w
                home[jname], i = [*map(float, qpos[i : i + 3]), *map(float, q)], i + 7
        return home

    # ------------------------------------------------------------------ output
    def urdf(self) -> str:
        robot = ET.Element("robot", name=self.name)
        for link in self.links:
            ET.SubElement(robot, "link", name=link)
        for j in self.joints:
            e = ET.SubElement(robot, "joint", name=j["name"], type=j["type"])
            ET.SubElement(e, "parent", link=j["parent"])
            ET.SubElement(e, "child", link=j["child"])
            M = j["origin"]
            ET.SubElement(e, "origin", xyz=" ".join(repr(float(v)) for v in M.translation),
                          rpy=" ".join(repr(float(v)) for v in pin.rpy.matrixToRpy(M.rotation)))
            if j["axis"] is not None:
                ET.SubElement(e, "axis", xyz=" ".join(repr(float(v)) for v in j["axis"]))
                lo, hi = j["limits"]
                ET.SubElement(e, "limit", lower=repr(float(lo)), upper=repr(float(hi)),
                              effort="0", velocity="0")
        ET.indent(robot)
        return ET.tostring(robot, encoding="unicode") + "\n"


def mjcf_to_urdf(source: str | Path, *, name: str | None = None,
                 keyframe: str | None = None) -> tuple[str, dict[str, Any]]:
    """Translate MJCF into URDF text and a pincal sidecar (mapping in the module docstring).

    Args:
        source: an MJCF file path, or MJCF text (a string starting with ``<``).
        name: robot name when ``<mujoco model=...>`` is absent (default: file stem).
        keyframe: keyframe whose ``qpos`` is the home guess (default: ``home``, else the
            first keyframe, else ``qpos0``).

    Returns:
        ``(urdf_xml, sidecar)``; the sidecar has ``closed_loop``, ``type``, ``name_mot``
        (when actuators drive joints), ``home`` [m, rad], ``measured_frame`` (the last
        leaf body), ``mjcf_equality`` and ``mjcf_actuators``.

    Raises:
        ModelFileError: unreadable or unsupported MJCF. UnknownNameError: a reference to a
        body, site, joint, class or keyframe that does not exist.
    """
    text = str(source)
    if not (isinstance(source, str) and text.lstrip().startswith("<")):
        path = Path(source)
        name = name or path.stem
        try:
            text = path.read_text(encoding="utf-8")
        except OSError as exc:
            raise ModelFileError(f"cannot read MJCF file {str(path)!r}: {exc.strerror}") from exc
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise ModelFileError(f"MJCF is not well-formed XML: {exc}") from exc
    conv = _Converter(root, name or "mjcf")
    conv.convert_tree()
    pairs, kinds, eq_names = conv.closures()
    actuators = conv.actuators()
    sidecar: dict[str, Any] = {}
    if pairs:
        sidecar |= {"closed_loop": pairs, "type": kinds}
    if actuators:
        sidecar["name_mot"] = list(dict.fromkeys(actuators.values()))
    sidecar["home"] = conv.home(keyframe)
    sidecar["measured_frame"] = conv.leaves[-1]
    sidecar |= {"mjcf_equality": eq_names, "mjcf_actuators": actuators}
    return conv.urdf(), sidecar


def load_mjcf(path: str | Path, measured_frame: str | None = None, *,
              actuated: list[str] | None = None, keyframe: str | None = None,
              options: Any = None) -> Any:
    """Load an MJCF file as a :class:`~pincal.model.Mechanism` (via :func:`mjcf_to_urdf`).

    A sidecar ``<stem>.yaml`` beside the file, if present, is merged over the derived
    keys (to add presets, a workspace, ``measured``, or to override them).

    Args:
        path: the ``.xml`` file.
        measured_frame: link to measure (default: sidecar, else the last leaf body).
        actuated: actuated joint names, overriding the MJCF actuators.
        keyframe: keyframe giving the home guess (see :func:`mjcf_to_urdf`).
        options: :class:`~pincal.model.SolverOptions`.

    Returns:
        The Mechanism; ``urdf_xml`` is the converted URDF, so export writes URDF.

    Raises:
        ModelFileError, UnknownNameError, ClosureError, MobilityError.
    """
    from pincal.model import Mechanism, read_sidecar

    path = Path(path)
    urdf, sidecar = mjcf_to_urdf(path, keyframe=keyframe)
    extra = path.with_suffix(".yaml")
    if extra.is_file():
        sidecar |= read_sidecar(extra)
    if actuated is not None:
        sidecar["name_mot"] = list(actuated)
    return Mechanism(urdf, sidecar, name=path.stem, source=path, measured_frame=measured_frame,
                     options=options)
