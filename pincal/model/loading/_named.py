"""Robots loaded by name: local sidecars, locked joints, example-robot-data defaults.

A *local sidecar* is a YAML file that describes a robot kept elsewhere; its key
``robot`` names it (an example-robot-data or bundled name, a model directory or a URDF
path, relative paths being relative to the file)::

    # my_tiago.yaml — used as `pincal info my_tiago.yaml` (or a directory holding it)
    robot: tiago
    measured_frame: arm_7_link
    lock: {torso_lift_joint: 0.2, arm_1_joint: home}  # made fixed [rad or m, or home]
    columns: {torso1: torso_lift_joint}             # measurement-file column → joint

The same file can be given to any command with ``--sidecar FILE`` beside a model
(its ``robot`` key, if present, must then name that model). Its keys replace those of
the robot's own sidecar one by one. ``--frame`` and ``--lock`` on the command line win
over the file.

A robot of example-robot-data without a pincal sidecar gets (each said in a note):

- ``home``: the SRDF reference configuration (``group_state``: ``home``, ``ready``,
  ``default``, ``half_sitting``… else the first) of the package's SRDF for that URDF;
- sampling ranges: a revolute joint whose URDF range is wider than one turn is sampled
  over one turn centred on home (angles beyond repeat the same poses);
- without an SRDF pose, a searched regular home, and for an open chain standing on its
  base a floor under drawn poses (applied by :func:`pincal.model.load_mechanism`, see
  :mod:`pincal.model.reach._home_search`).
"""

from __future__ import annotations

import math
import os
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pincal._files import read_text
from pincal._yaml import shown
from pincal.errors import ModelFileError
from pincal.model.files import UrdfTree
from pincal.model.loading._lock_values import lock_values
from pincal.model.loading._model_files import bundled_models, read_sidecar, resolve_model_path

__all__ = [
    "LOADER_KEYS",
    "NamedModel",
    "find_local_sidecar",
    "model_record",
    "resolve_named",
    "srdf_home",
]

#: sidecar keys the loader consumes (not part of the typed :class:`Sidecar`)
LOADER_KEYS = ("robot", "lock")
#: group_state names taken as home, best first
_HOME_STATES = ("home", "ready", "default", "half_sitting", "neutral", "standing")
_YAML = (".yaml", ".yml")


@dataclass(frozen=True)
class NamedModel:
    """A resolved model spec.

    Attributes:
        urdf: the URDF file.
        sidecar: the merged sidecar mapping (loader keys removed).
        lock: joints to make fixed ``{name: value}`` [rad or m], or ``"home"`` (the
            joint's home value).
        local: the local sidecar file, if one was used.
        notes: what was loaded and which defaults were applied, for the user.
        erd_defaults: whether example-robot-data defaults were applied (no sidecar).
        turns: default sampling ranges ``{joint: [lower, upper]}`` [rad] of joints whose
            URDF range is over one turn (not in ``sidecar``: the loader keeps those of
            the actuated joints), {} when a sidecar gives the workspace.
    """

    urdf: Path
    sidecar: dict[str, Any]
    lock: dict[str, float | str]
    local: Path | None
    notes: tuple[str, ...]
    erd_defaults: bool
    turns: dict[str, list[float]]


def find_local_sidecar(spec: str | Path) -> Path | None:
    """The local sidecar a model spec names, if any.

    A ``.yaml`` file, or a directory without a URDF holding ``<dir>.yaml`` (or a single
    YAML file) with a ``robot`` key.
    """
    path = Path(spec)
    if path.suffix.lower() in _YAML and path.is_file():
        return path
    if path.is_dir() and not any(path.glob("*.urdf")):
        own = [p for p in (path / f"{path.name}{ext}" for ext in _YAML) if p.is_file()]
        found = own or sorted(p for ext in _YAML for p in path.glob(f"*{ext}"))
        if len(found) == 1 and "robot" in read_sidecar(found[0]):
            return found[0]
    return None


def _robot_spec(local: Path, data: Mapping[str, Any]) -> str:
    robot = data.get("robot")
    if (not isinstance(robot, str) or not robot) and local.with_suffix(".urdf").is_file():
        raise ModelFileError(
            f"{shown(str(local))} is the sidecar of {local.with_suffix('.urdf').name}: give "
            f"that URDF or its directory as the model"
        )
    if not isinstance(robot, str) or not robot:
        raise ModelFileError(
            f"sidecar {shown(str(local))} is given as the model but has no 'robot' key naming "
            "the robot it describes (e.g. `robot: ur5`, a model directory or a .urdf path)"
        )
    beside = local.parent / robot
    return str(beside) if _path_like(robot) and beside.exists() else robot


def _path_like(robot: str) -> bool:
    """A sidecar's ``robot`` names a path (else a robot name, never a local path)."""
    return os.sep in robot or robot.endswith(".urdf")


def _shadow_note(spec: str, urdf: Path) -> str | None:
    """A note when a local path named like a known robot was loaded instead of it."""
    if os.sep in spec or not Path(spec).exists():
        return None
    from pincal.model.loading._robots import example_robot_names

    known = [f"bundled model {spec!r}"] if spec in bundled_models() else []
    try:
        if spec in example_robot_names():
            known.append(f"example-robot-data robot {spec!r}")
    except ModelFileError:
        pass
    if not known:
        return None
    return (
        f"model {spec!r} is the local path ./{spec} ({urdf}), not the {' nor the '.join(known)}; "
        f"rename the local path (or run elsewhere) to load the latter"
    )


def _is_erd(urdf: Path) -> bool:
    return any(p.name == "robots" and p.parent.name == "example-robot-data" for p in urdf.parents)


def _srdf_file(urdf: Path) -> Path | None:
    srdf_dir = next((p / "srdf" for p in urdf.parents if (p / "srdf").is_dir()), None)
    if srdf_dir is None:
        return None
    stems = {p.stem: p for p in srdf_dir.glob("*.srdf")}
    for stem in (urdf.stem, urdf.stem.removesuffix("_robot")):
        if stem in stems:
            return stems[stem]
    prefixes = sorted((s for s in stems if urdf.stem.startswith(s)), key=len, reverse=True)
    return stems[prefixes[0]] if prefixes else None


def srdf_home(urdf: Path, tree: UrdfTree) -> tuple[dict[str, float], str] | None:
    """The SRDF reference configuration of an example-robot-data URDF, if it has one.

    Returns:
        ({joint: value} [rad or m] for the URDF's 1-dof joints, "state 'name' of file"),
        or None when the package has no SRDF for the URDF or it has no ``group_state``.
    """
    srdf = _srdf_file(urdf)
    if srdf is None:
        return None
    try:
        root = ET.fromstring(read_text(srdf, "SRDF", error=ModelFileError))
    except ET.ParseError:
        return None
    states = root.findall("group_state")
    names = [str(s.get("name")) for s in states]
    if not states:
        return None
    chosen = next((n for n in _HOME_STATES if n in names), names[0])
    home: dict[str, float] = {}
    for state in states:
        if state.get("name") != chosen:
            continue
        for j in state.findall("joint"):
            name, value = str(j.get("name")), j.get("value", "")
            uj = tree.joints.get(name)
            if uj is None or not uj.movable or uj.type == "floating":
                continue
            try:
                home[name] = float(value.split()[0])
            except (ValueError, IndexError):
                continue
    return (home, f"state {chosen!r} of {srdf.name}") if home else None


def _erd_defaults(urdf: Path, xml: str) -> dict[str, tuple[Any, str]]:
    """Sidecar keys for an example-robot-data robot without one: ``{key: (value, note)}``."""
    tree = UrdfTree(xml, source=urdf)
    out: dict[str, tuple[Any, str]] = {}
    found = srdf_home(urdf, tree)
    home = found[0] if found else {}
    if found:
        out["home"] = (home, f"home: the SRDF reference configuration ({found[1]})")
    turns = {}
    for e in ET.fromstring(xml).findall("joint"):
        lim = e.find("limit")
        if e.get("type") != "revolute" or lim is None:
            continue
        try:
            lo, hi = float(lim.get("lower", "0")), float(lim.get("upper", "0"))
        except ValueError:
            continue
        if hi - lo > 2 * math.pi + 1e-6:
            name = str(e.get("name"))
            h = home.get(name, min(max(0.0, lo), hi))
            turns[name] = [max(lo, h - math.pi), min(hi, h + math.pi)]
    if turns:  # the loader keeps the actuated ones and says so (:func:`turn_note`)
        out["workspace"] = ({"joints": turns}, "")
    return out


def turn_note(names: list[str]) -> str:
    """The note about joints sampled over one turn (example-robot-data defaults)."""
    return (
        f"{len(names)} joint(s) with a URDF range over one turn are sampled over one turn "
        f"around home: {', '.join(names)} (example-robot-data default, no sidecar sets it; "
        f"a sidecar workspace 'joints' changes this)"
    )


def resolve_named(
    spec: str | Path,
    sidecar_file: str | Path | Mapping[str, Any] | None = None,
    lock: Mapping[str, float | str] | None = None,
) -> NamedModel:
    """Resolve a model spec with its local sidecar, locks and defaults (see module doc).

    ``sidecar_file`` may be the sidecar's keys already read (a mapping without ``robot``:
    a calibration's own model record once its model was found moved).

    Raises:
        ModelFileError: a local sidecar without ``robot``, a ``--sidecar`` whose ``robot``
            names another model, a bad ``lock`` value; UnknownNameError: unknown name.
    """
    local = find_local_sidecar(spec)
    notes: list[str] = []
    if local is not None and sidecar_file is not None:
        raise ModelFileError(
            f"the model {shown(str(spec))} is already a sidecar file; give --sidecar only "
            "beside a robot name, directory or URDF"
        )
    data: dict[str, Any] = {}
    robot = str(spec)
    by_name = False  # a bare robot name in a sidecar is a name, never a local path
    if local is not None:
        data = dict(read_sidecar(local))
        robot = _robot_spec(local, data)
        by_name = not _path_like(str(data["robot"]))
    elif isinstance(sidecar_file, Mapping):
        data = {k: v for k, v in sidecar_file.items() if k != "robot"}
    elif sidecar_file is not None:
        local = Path(sidecar_file)
        data = dict(read_sidecar(local))
        if "robot" in data:
            by = not _path_like(str(data["robot"]))
            named = resolve_model_path(_robot_spec(local, data), by_name=by)[0].resolve()
            if named != resolve_model_path(spec)[0].resolve():
                raise ModelFileError(
                    f"--sidecar {shown(str(local))} describes robot {shown(data['robot'])}, "
                    f"not the model {shown(str(spec))}; give the matching model or drop the key"
                )
    urdf, own = resolve_model_path(robot, by_name=by_name)
    shadow = None if by_name else _shadow_note(robot, urdf)
    if shadow:
        notes.append(shadow)
    if local is not None:
        notes.append(f"sidecar {local} describes {robot!r} ({urdf})")
    base = dict(read_sidecar(own)) if own else {}
    erd = own is None and _is_erd(urdf)
    turns: dict[str, list[float]] = {}
    if erd:
        xml = read_text(urdf, "URDF", error=ModelFileError)
        for key, (value, note) in _erd_defaults(urdf, xml).items():
            if key in data:
                continue
            if key == "workspace":
                turns = value["joints"]
                continue
            base[key] = value
            notes.append(f"{note} (example-robot-data default, no sidecar sets it)")
    locks = (
        lock_values(base.get("lock"), f"sidecar {own}")
        | lock_values(data.get("lock"), f"sidecar {local}")
        | dict(lock or {})
    )
    merged = {k: v for k, v in (base | data).items() if k not in LOADER_KEYS}
    return NamedModel(urdf, merged, locks, local, tuple(dict.fromkeys(notes)), erd, turns)


def model_record(
    spec: str | Path,
    sidecar_file: str | Path | None = None,
    frame: str | None = None,
    lock: Mapping[str, float | str] | None = None,
) -> dict[str, Any]:
    """A local sidecar mapping that reloads ``spec`` with these options from anywhere.

    Its ``robot`` is an absolute path when the robot is a local path, else the name.
    """
    local = find_local_sidecar(spec) or (Path(sidecar_file) if sidecar_file else None)
    doc: dict[str, Any] = dict(read_sidecar(local)) if local is not None else {}
    from_file = sidecar_file is None and local is not None and "robot" in doc
    if not (from_file and not _path_like(str(doc["robot"]))):  # a robot name stays a name
        robot = _robot_spec(local, doc) if from_file and local is not None else str(spec)
        doc["robot"] = str(Path(robot).resolve()) if Path(robot).exists() else robot
    return _with_options(doc, frame, lock)


def _with_options(
    doc: dict[str, Any], frame: str | None, lock: Mapping[str, float | str] | None
) -> dict[str, Any]:
    if frame:
        doc["measured_frame"] = frame
    if lock:
        doc["lock"] = {**lock_values(doc.get("lock"), "sidecar"), **dict(lock)}
    return doc
