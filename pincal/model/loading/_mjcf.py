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
  sidecar key ``closure_names``;
* actuators with ``joint=`` give ``name_mot`` (names in ``actuator_names``); the
  ``home`` guess is the keyframe ``home`` (else the first keyframe, else ``qpos0``;
  a ``home:`` in the sidecar beside the file overrides it). A singular ``qpos0`` is
  replaced by a regular configuration nearby, a home outside a joint's range and
  joints with springs (``stiffness``) are reported (:mod:`pincal.model.loading._mjcf_home`).

Active joint/tendon/flex equalities (a joint ``polycoef`` coupling) and ``<include>`` are
refused (:class:`ModelFileError`, one line saying what to do instead);
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

from pincal._files import read_text
from pincal.errors import ModelFileError, UnknownNameError
from pincal.model._mechanism import Mechanism
from pincal.model.files import MjcfTree, UrdfTree, euler_xyz, quat_matrix, unit, vec
from pincal.model.loading._lock_values import lock_values, lock_values_at_home
from pincal.model.loading._mjcf_home import build_with_home
from pincal.model.loading._model_files import read_sidecar
from pincal.model.loading._serial import lock_joints
from pincal.model.loops import SolverOptions

__all__ = ["load_mjcf", "mjcf_to_urdf"]

log = logging.getLogger(__name__)

ACTUATOR_TAGS = (
    "motor",
    "position",
    "velocity",
    "general",
    "intvelocity",
    "damper",
    "cylinder",
    "muscle",
    "adhesion",
)


class _Converter(MjcfTree):
    """The tree plus MJCF's equality, actuator and keyframe sections."""

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
            a = self.attrs(e, "main", "equality")
            name = a.get("name") or f"{e.tag}{k}"
            if a.get("active", "true") == "false":
                log.warning("MJCF import: inactive equality %r skipped", name)
                continue
            if e.tag not in ("connect", "weld"):
                raise ModelFileError(_refusal(e.tag, a, name))
            if "site1" in a or "site2" in a:
                pair = [self._site(a.get("site1", "")), self._site(a.get("site2", ""))]
            else:
                b1, b2 = self._body_of(a.get("body1")), self._body_of(a.get("body2"))
                X1, X2 = self.body_world[b1], self.body_world[b2]
                if e.tag == "connect":
                    anchor = vec(a.get("anchor"), 3, f"connect {name!r} anchor")
                    Ta = pin.SE3(np.eye(3), anchor)
                    Tb = pin.SE3(np.eye(3), X2.actInv(X1.act(anchor)))
                else:
                    Tb = pin.SE3(np.eye(3), vec(a.get("anchor"), 3, f"weld {name!r} anchor"))
                    rel = vec(a.get("relpose", "0 1 0 0 0 0 0"), 7, f"weld {name!r} relpose")
                    Ta = (
                        X1.actInv(X2) * Tb
                        if not rel[3:].any()
                        else pin.SE3(quat_matrix(rel[3:], f"weld {name!r}"), rel[:3])
                    )
                pair = [
                    self.fresh(f"{name}_1", self.used_links),
                    self.fresh(f"{name}_2", self.used_links),
                ]
                self.fixed(self.body_link[b1], pair[0], Ta)
                self.fixed(self.body_link[b2], pair[1], Tb)
            pairs.append(pair)
            kinds.append("3d" if e.tag == "connect" else "6d")
            names.append(name)
        return pairs, kinds, names

    def actuators(self) -> dict[str, str]:
        out: dict[str, str] = {}
        for k, e in enumerate(self._section("actuator")):
            a = self.attrs(e, "main")
            name = a.get("name") or f"{e.tag}{k}"
            target = a.get("joint") or a.get("jointinparent")
            if e.tag not in ACTUATOR_TAGS or target is None:
                log.warning(
                    "MJCF import: actuator %r (<%s>) has no joint transmission and is "
                    "skipped; declare the actuated joints with load_mjcf(actuated=...)",
                    name,
                    e.tag,
                )
                continue
            if target not in self.mj_joints:
                raise UnknownNameError("MJCF joint", target, list(self.mj_joints))
            if self.mj_joints[target][0] not in ("hinge", "slide"):
                raise ModelFileError(
                    f"MJCF actuator {name!r} drives the "
                    f"{self.mj_joints[target][0]} joint {target!r}; pincal "
                    "actuates 1-dof (hinge/slide) joints only"
                )
            out[name] = target
        return out

    def home(self, keyframe: str | None) -> dict[str, Any]:
        keys = self.root.findall("keyframe/key")
        named = [k for k in keys if k.get("name") == (keyframe or "home")]
        if keyframe is not None and not named:
            raise UnknownNameError("MJCF keyframe", keyframe, [k.get("name", "") for k in keys])
        key = named[0] if named else (keys[0] if keys else None)
        qpos = np.array(self.qpos0)
        self.home_source = "qpos0"
        if key is not None and key.get("qpos") is not None:
            qpos = vec(key.get("qpos"), qpos.size, f"keyframe {key.get('name', '')!r} qpos")
            self.home_source = f"keyframe {key.get('name', '')!r}"
        home: dict[str, Any] = {}
        i = 0
        for jname, (kind, urdf) in self.mj_joints.items():
            if kind in ("hinge", "slide"):
                home[jname], i = float(qpos[i]), i + 1
            elif kind == "ball":
                angles = euler_xyz(quat_matrix(qpos[i : i + 4], f"ball {jname!r} qpos"))
                home.update(zip(urdf, angles, strict=True))
                i += 4
            else:
                w = qpos[i + 3 : i + 7]
                q = pin.Quaternion(*unit(w, f"free {jname!r} qpos")).coeffs()  # x y z w
                home[jname], i = [*map(float, qpos[i : i + 3]), *map(float, q)], i + 7
        return home


def _refusal(tag: str, a: dict[str, str], name: str) -> str:
    """The one-line refusal of an active ``<equality><tag>`` other than connect and weld."""
    head = f"MJCF <equality><{tag}> {name!r} is not supported"
    if tag == "joint":
        j1, j2 = a.get("joint1", "?"), a.get("joint2")
        poly = a.get("polycoef", "0 1 0 0 0")
        if j2 is None:
            return (
                f"{head}: it holds joint {j1!r} at a value (polycoef {poly!r}), not a frame; "
                f"remove it and fix the joint with 'lock: {{{j1}: VALUE}}' [rad or m] in a "
                "sidecar <stem>.yaml beside the MJCF"
            )
        return (
            f"{head}: it couples joint {j1!r} to joint {j2!r} by a polynomial (polycoef "
            f"{poly!r}), and pincal closes loops between frames only; model the linkage "
            "that makes the coupling (its bodies, closed by <connect> or <weld>), or remove "
            f"the equality and drive both joints (load_mjcf(actuated=[..., {j1!r}, {j2!r}]) "
            "or the sidecar 'name_mot')"
        )
    if tag == "tendon":
        return (
            f"{head}: it couples tendon lengths ({a.get('tendon1', '?')!r}"
            + (f", {a['tendon2']!r}" if "tendon2" in a else "")
            + "), and pincal models rigid links; model the tendon's path as a linkage closed "
            "by <connect>, or remove the equality and declare the actuated joints "
            "(load_mjcf(actuated=[...]) or the sidecar 'name_mot')"
        )
    return (
        f"{head}: only connect (3d) and weld (6d) closures between frames are; remove it, "
        "or model what it constrains as bodies closed by <connect> or <weld>"
    )


def mjcf_to_urdf(
    source: str | Path, *, name: str | None = None, keyframe: str | None = None
) -> tuple[str, dict[str, Any]]:
    """Translate MJCF into URDF text and a pincal sidecar (mapping in the module docstring).

    Args:
        source: an MJCF file path, or MJCF text (a string starting with ``<``).
        name: robot name when ``<mujoco model=...>`` is absent (default: file stem).
        keyframe: keyframe whose ``qpos`` is the home guess (default: ``home``, else the
            first keyframe, else ``qpos0``).

    Returns:
        ``(urdf_xml, sidecar)``; the sidecar has ``closed_loop``, ``type``, ``name_mot``
        (when actuators drive joints), ``home`` [m, rad], ``measured_frame`` (the last
        leaf body), ``closure_names`` and ``actuator_names``.

    Raises:
        ModelFileError: unreadable or unsupported MJCF. UnknownNameError: a reference to a
        body, site, joint, class or keyframe that does not exist.
    """
    urdf, sidecar, _ = _convert(source, name, keyframe)
    return urdf, sidecar


def _convert(
    source: str | Path, name: str | None, keyframe: str | None
) -> tuple[str, dict[str, Any], _Converter]:
    """:func:`mjcf_to_urdf`, and the converter (ranges, springs, where home came from)."""
    text = str(source)
    if not (isinstance(source, str) and text.lstrip().startswith("<")):
        path = Path(source)
        name = name or path.stem
        text = read_text(path, "MJCF file", error=ModelFileError)
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
    sidecar |= {"closure_names": eq_names, "actuator_names": actuators}
    return conv.urdf(), sidecar, conv


def load_mjcf(
    path: str | Path,
    measured_frame: str | None = None,
    *,
    actuated: list[str] | None = None,
    keyframe: str | None = None,
    options: SolverOptions | None = None,
    lock: dict[str, float | str] | None = None,
) -> Mechanism:
    """Load an MJCF file as a :class:`~pincal.model.Mechanism` (via :func:`mjcf_to_urdf`).

    A sidecar ``<stem>.yaml`` beside the file, if present, is merged over the derived
    keys (to add presets, a workspace, ``measured``, or to override them). Its ``lock:``
    (as for robots by name: ``{joint: value}`` [rad or m] or ``home``) makes joints
    fixed, e.g. a spring joint (MJCF ``stiffness``) a calibration should not treat as a
    free passive joint; ``home`` is the joint's value at the file's home (keyframe,
    sidecar ``home:`` or ``qpos0``).

    Args:
        path: the ``.xml`` file.
        measured_frame: link to measure (default: sidecar, else the last leaf body).
        actuated: actuated joint names, overriding the MJCF actuators.
        keyframe: keyframe giving the home guess (see :func:`mjcf_to_urdf`).
        options: :class:`~pincal.model.SolverOptions`.
        lock: joints to make fixed (wins over the sidecar's ``lock``).

    Returns:
        The Mechanism; ``urdf_xml`` is the converted URDF, so export writes URDF.

    Raises:
        ModelFileError, UnknownNameError, ClosureError, MobilityError,
        SingularConfigurationError: no home assembles (the message names joints the
        home puts outside their ranges).
    """
    path = Path(path)
    urdf, sidecar, conv = _convert(path, None, keyframe)
    source = conv.home_source
    extra = path.with_suffix(".yaml")
    locks: dict[str, float | str] = {}
    if extra.is_file():
        own = dict(read_sidecar(extra))
        locks = lock_values(own.pop("lock", None), f"sidecar {extra}")
        source = "sidecar" if "home" in own else source
        sidecar |= own
    locks |= dict(lock or {})
    if actuated is not None:
        sidecar["name_mot"] = list(actuated)
    urdf, stiffness, locked = _lock(urdf, sidecar, locks, conv.stiffness)

    def build(sc: dict[str, Any]) -> Mechanism:
        return Mechanism(
            urdf, sc, name=path.stem, source=path, measured_frame=measured_frame, options=options
        )

    mech = build_with_home(build, sidecar, source, conv.ranges, stiffness)
    return mech.with_notes(before=[locked]) if locked else mech


def _lock(
    urdf: str,
    sidecar: dict[str, Any],
    locks: dict[str, float | str],
    stiffness: dict[str, float],
) -> tuple[str, dict[str, float], str]:
    """Lock joints of the converted URDF, in place on ``sidecar`` (see :func:`load_mjcf`).

    Returns:
        The URDF text, the springs left movable, and the note saying what was locked
        ("" when nothing).

    Raises:
        UnknownNameError: a locked name is not a movable joint.
    """
    if not locks:
        return urdf, stiffness, ""
    values = lock_values_at_home(locks, sidecar.get("home"))
    urdf = lock_joints(urdf, values)
    gone = set(values) | {n for n, j in UrdfTree(urdf).joints.items() if not j.movable}
    if sidecar.get("name_mot") is not None:
        sidecar["name_mot"] = [n for n in sidecar["name_mot"] if n not in gone]
    if isinstance(sidecar.get("home"), dict):
        sidecar["home"] = {k: v for k, v in sidecar["home"].items() if k not in gone}
    if isinstance(sidecar.get("actuator_names"), dict):
        sidecar["actuator_names"] = {
            a: j for a, j in sidecar["actuator_names"].items() if j not in gone
        }
    said = [
        f"{k} = {v:.6g}"
        + (f" (a spring, MJCF stiffness {stiffness[k]:g})" if k in stiffness else "")
        for k, v in values.items()
    ]
    kept = {j: k for j, k in stiffness.items() if j not in gone}
    return urdf, kept, f"locked (lock: in the sidecar or asked): {', '.join(said)}"
