"""The sidecar: what a URDF cannot say (loop closures, actuation, measured frame, ...).

:class:`Sidecar` is the typed, frozen form of the ``<model>.yaml`` file beside a URDF.
:meth:`Sidecar.from_dict` checks every key and value type (names are checked later
against the URDF by :class:`~pincal.model.Mechanism`) and refuses unknown keys with
a suggestion; :meth:`Sidecar.to_dict` gives back a YAML-safe mapping.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import Any

from pincal._yaml import shown
from pincal.errors import ModelFileError
from pincal.model.files._closures import COMPONENTS, parse_components
from pincal.model.files._readings import JointReadings

__all__ = ["JOINT_KINDS", "WORKSPACE_POSE_KEYS", "Sidecar", "Workspace", "validate_sidecar"]

WORKSPACE_POSE_KEYS = ("x", "y", "z", "rx", "ry", "rz")
#: joint kinds the ``joint_type`` key accepts (lower case; YAML files may use upper case):
#: ``spherical``, ``universal`` (first axis = the URDF ``<axis>``), ``ujoint_<a><b>``
#: (revolute about the joint frame's axis a, then about its axis b; the robot.yaml
#: collection's own names) and ``fixed`` (the joint locked at 0); see
#: :mod:`pincal.model.files._build`
JOINT_KINDS = (
    "spherical",
    "universal",
    *(f"ujoint_{a}{b}" for a in "xyz" for b in "xyz" if a != b),
    "fixed",
)

ClosureKind = str | tuple[str, ...]


@dataclass(frozen=True)
class Workspace:
    """Limits for random measurement poses.

    Attributes:
        pose: measured-frame pose ranges; keys among x, y, z (world position [m]) and
            rx, ry, rz (rotation vector relative to the home orientation [rad]).
        joints: actuated-joint ranges [m or rad] (URDF limits where not given).
        floor: height [m] above the base plane z = 0 that every moving link frame and
            joint origin keeps in drawn poses (see :mod:`pincal.model.reach._floor`); None:
            no floor (YAML ``floor: false``).
    """

    pose: dict[str, tuple[float, float]] = field(default_factory=dict)
    joints: dict[str, tuple[float, float]] = field(default_factory=dict)
    floor: float | None = None


def _is_number(v: Any) -> bool:
    """A finite int or float that converts to a finite float (a 400-digit int does not)."""
    if isinstance(v, bool):
        return False
    if isinstance(v, int):
        return v.bit_length() <= 1023
    return isinstance(v, float) and math.isfinite(v)


def _q(v: Any) -> str:
    """Bounded text of a user value for messages."""
    return shown(v)


def _names(v: Any, key: str) -> tuple[str, ...]:
    """A name or a list of names as a tuple (the YAML forms ``a`` and ``[a, b]``)."""
    if isinstance(v, str):
        return (v,)
    if isinstance(v, list | tuple) and all(isinstance(x, str) for x in v):
        return tuple(v)
    raise ModelFileError(f"sidecar {_q(key)} must be a name or a list of names: {_q(v)}")


def _range(v: Any, where: str) -> tuple[float, float]:
    if not (isinstance(v, list | tuple) and len(v) == 2 and all(_is_number(x) for x in v)):
        raise ModelFileError(f"sidecar {where} must be [lower, upper] finite numbers, got {_q(v)}")
    if float(v[0]) > float(v[1]):
        raise ModelFileError(f"sidecar {where}: lower {_q(v[0])} is above upper {_q(v[1])}")
    return float(v[0]), float(v[1])


def _check_components(spec: Any, what: str) -> None:
    """parse_components with the offending value clipped in the message."""
    try:
        parse_components(spec, what)
    except ModelFileError:
        valid = ", ".join(["3d", "6d", "pose", "position", "orientation", *COMPONENTS])
        raise ModelFileError(f"{what}: invalid components {_q(spec)}; use one of {valid}") from None


def _closure_pairs(v: Any) -> tuple[tuple[str, str], ...]:
    if v is None:
        return ()
    if not isinstance(v, list | tuple):
        raise ModelFileError("sidecar 'closed_loop' must be a list of [frame_a, frame_b] pairs")
    pairs = []
    for k, pair in enumerate(v):
        if not (
            isinstance(pair, list | tuple)
            and len(pair) == 2
            and all(isinstance(p, str) for p in pair)
        ):
            raise ModelFileError(
                f"sidecar closed_loop[{k}] must be a pair of frame names, got {_q(pair)}"
            )
        pairs.append((pair[0], pair[1]))
    return tuple(pairs)


def _closure_kinds(v: Any, n_pairs: int) -> tuple[ClosureKind, ...]:
    """One closure kind per pair: a kind name (``3d``, ``6d``...) or a component tuple.

    A single kind, or a single component list, applies to every pair.
    """
    if v is None:
        v = "3d"
    if isinstance(v, str) or (
        isinstance(v, list | tuple) and v and all(t in COMPONENTS for t in v)
    ):
        kinds = [v] * n_pairs
    elif isinstance(v, list | tuple) and len(v) == 1:
        kinds = list(v) * n_pairs
    elif isinstance(v, list | tuple):
        kinds = list(v)
    else:
        raise ModelFileError(f"sidecar 'type' must be a closure type or a list of them: {_q(v)}")
    if len(kinds) != n_pairs:
        raise ModelFileError(
            f"sidecar 'type' must give one closure type per pair ({n_pairs} pairs), got {_q(v)}"
        )
    out: list[ClosureKind] = []
    for k, kind in enumerate(kinds):
        if not (isinstance(kind, str) or isinstance(kind, list | tuple)):
            raise ModelFileError(f"sidecar type[{k}] must be a closure type, got {_q(kind)}")
        if not isinstance(kind, str) and not all(isinstance(c, str) for c in kind):
            raise ModelFileError(f"sidecar type[{k}] must list component names, got {_q(kind)}")
        _check_components(kind, f"sidecar type[{k}]")
        out.append(kind if isinstance(kind, str) else tuple(kind))
    return tuple(out)


def _home(v: Any) -> dict[str, tuple[float, ...]]:
    if v is None:
        return {}
    if not isinstance(v, Mapping):
        raise ModelFileError("sidecar 'home' must map joint names to values [m, rad]")
    out = {}
    for name, value in v.items():
        vals = value if isinstance(value, list | tuple) else [value]
        if not vals or not all(_is_number(x) for x in vals):
            raise ModelFileError(
                f"sidecar home[{_q(name)}] must be a finite number or a list of them, "
                f"got {_q(value)}"
            )
        out[str(name)] = tuple(float(x) for x in vals)
    return out


def _workspace(v: Any) -> Workspace:
    if v is None:
        return Workspace()
    if not isinstance(v, Mapping):
        raise ModelFileError(
            "sidecar 'workspace' must be a mapping with 'pose', 'joints' and/or 'floor'"
        )
    _refuse_unknown(v, ("pose", "joints", "floor"), "workspace key")
    parts: dict[str, dict[str, tuple[float, float]]] = {}
    for part in ("pose", "joints"):
        ranges = v.get(part)
        parts[part] = {}
        if ranges is None:
            continue
        if not isinstance(ranges, Mapping):
            raise ModelFileError(f"sidecar workspace.{part} must map names to [lower, upper]")
        for name, r in ranges.items():
            if part == "pose" and name not in WORKSPACE_POSE_KEYS:
                _refuse_unknown({name: r}, WORKSPACE_POSE_KEYS, "workspace pose key")
            parts[part][str(name)] = _range(r, f"workspace.{part}[{_q(name)}]")
    floor = v.get("floor")
    if floor is not None and floor is not False and not _is_number(floor):
        raise ModelFileError(
            f"sidecar workspace.floor must be a height [m] above the base plane z = 0 (e.g. "
            f"0.05) or false (no floor check), got {_q(floor)}"
        )
    off = floor is None or floor is False  # `floor: 0` is a floor at the base plane
    return Workspace(parts["pose"], parts["joints"], None if off else float(floor or 0.0))


def _presets(v: Any) -> dict[str, list[Any]]:
    if v is None:
        return {}
    if not isinstance(v, Mapping):
        raise ModelFileError("sidecar 'presets' must map preset names to lists of entries")
    for name, entries in v.items():
        if not isinstance(entries, list):
            raise ModelFileError(f"sidecar preset {_q(name)} must be a list of entries")
    return {str(k): list(e) for k, e in v.items()}


def _refuse_unknown(d: Mapping[Any, Any], valid: tuple[str, ...], what: str) -> None:
    for key in d:
        if key not in valid:
            near = difflib.get_close_matches(str(key), valid, n=1, cutoff=0.6)
            hint = f"did you mean {_q(near[0])}? " if near else ""
            raise ModelFileError(
                f"unknown sidecar {what} {_q(key)}: {hint}valid keys are {', '.join(valid)}"
            )


@dataclass(frozen=True)
class Sidecar:
    """Typed content of a sidecar file (all fields optional).

    Attributes:
        closed_loop: cut joints, pairs (frame_a, frame_b) of URDF link or joint names.
        type: one closure kind per pair: ``3d``, ``6d`` (any case) or a component tuple
            from x y z rx ry rz.
        name_mot: actuated joints, in actuator-vector order (None: every 1-dof joint of
            an open chain).
        joint_name, joint_type: URDF joints to turn into another joint kind (robot.yaml
            convention), one kind from :data:`JOINT_KINDS` per name.
        measured_frame: the frame the instrument measures (None: chosen automatically).
        measured: measured components, ``pose``, ``position`` or a component tuple.
        home: assembly guess per joint [m, rad] (floating joints: x y z roll pitch yaw).
        workspace: pose and actuator ranges for random poses.
        presets: named parameter lists (entries checked by :func:`pincal.parameters`).
        view_up: world direction drawn upwards by ``pincal view`` (``+z``, ``-z``...).
        measurement_regions: informational list (kept as written).
        closure_names: a name per closure pair (e.g. the MJCF equality names).
        actuator_names: ``{actuator: joint}`` (e.g. the MJCF actuator names).
        readings: how measurement files name and scale joint readings (YAML keys
            ``columns``, ``joint_units``, ``joint_reference``; see ``_readings``).
    """

    closed_loop: tuple[tuple[str, str], ...] = ()
    type: tuple[ClosureKind, ...] = ()
    name_mot: tuple[str, ...] | None = None
    joint_name: tuple[str, ...] = ()
    joint_type: tuple[str, ...] = ()
    measured_frame: str | None = None
    measured: ClosureKind = "pose"
    home: dict[str, tuple[float, ...]] = field(default_factory=dict)
    workspace: Workspace = field(default_factory=Workspace)
    presets: dict[str, list[Any]] = field(default_factory=dict)
    view_up: str | None = None
    measurement_regions: tuple[Any, ...] = ()
    closure_names: tuple[str, ...] = ()
    actuator_names: dict[str, str] = field(default_factory=dict)
    readings: JointReadings = field(default_factory=JointReadings)

    @classmethod
    def keys(cls) -> tuple[str, ...]:
        """The valid top-level keys."""
        names = tuple(f.name for f in fields(cls) if f.name != "readings")
        return (*names, "columns", "joint_units", "joint_reference")

    @classmethod
    def from_dict(cls, d: Mapping[str, Any] | Sidecar | None) -> Sidecar:
        """Check and convert a parsed sidecar mapping (None → empty sidecar).

        Raises:
            ModelFileError: an unknown key (with the nearest valid one), a wrong type, a
                non-finite number, an inverted range or mismatched lists.
        """
        if d is None:
            return cls()
        if isinstance(d, Sidecar):
            return d
        if not isinstance(d, Mapping):
            raise ModelFileError(f"sidecar must be a mapping, got {type(d).__name__}")
        _refuse_unknown(d, cls.keys(), "key")
        pairs = _closure_pairs(d.get("closed_loop"))
        name_mot = None if d.get("name_mot") is None else _names(d["name_mot"], "name_mot")
        joint_name = _names(d["joint_name"], "joint_name") if "joint_name" in d else ()
        joint_type = _names(d["joint_type"], "joint_type") if "joint_type" in d else ()
        if len(joint_type) == 1 and len(joint_name) > 1:
            joint_type = joint_type * len(joint_name)
        if len(joint_name) != len(joint_type):
            raise ModelFileError(
                f"sidecar 'joint_name' ({len(joint_name)} names) and 'joint_type' "
                f"({len(joint_type)} kinds) must have the same length"
            )
        kinds = tuple(t.strip().lower() for t in joint_type)
        for name, kind in zip(joint_name, kinds, strict=True):
            if kind not in JOINT_KINDS:
                raise ModelFileError(
                    f"sidecar joint_type {_q(kind)} of joint {_q(name)} is not supported; "
                    f"supported kinds: {', '.join(JOINT_KINDS)}"
                )
        frame = d.get("measured_frame")
        if frame is not None and not isinstance(frame, str):
            raise ModelFileError(f"sidecar 'measured_frame' must be a frame name: {_q(frame)}")
        measured = d.get("measured", "pose")
        measured = measured if isinstance(measured, str) else _names(measured, "measured")
        _check_components(measured, "sidecar 'measured'")
        view_up = d.get("view_up")
        if view_up is not None and not isinstance(view_up, str):
            raise ModelFileError(f"sidecar 'view_up' must be a direction such as -z: {_q(view_up)}")
        regions = d.get("measurement_regions") or []
        if not isinstance(regions, list):
            raise ModelFileError("sidecar 'measurement_regions' must be a list")
        closure_names = _names(d["closure_names"], "closure_names") if "closure_names" in d else ()
        if closure_names and len(closure_names) != len(pairs):
            raise ModelFileError(
                f"sidecar 'closure_names' ({len(closure_names)}) must name each of the "
                f"{len(pairs)} closed_loop pairs"
            )
        actuator_names = d.get("actuator_names") or {}
        if not isinstance(actuator_names, Mapping) or not all(
            isinstance(k, str) and isinstance(v, str) for k, v in actuator_names.items()
        ):
            raise ModelFileError("sidecar 'actuator_names' must map actuator names to joint names")
        return cls(
            closed_loop=pairs,
            type=_closure_kinds(d.get("type"), len(pairs)),
            name_mot=name_mot,
            joint_name=joint_name,
            joint_type=kinds,
            measured_frame=frame,
            measured=measured,
            home=_home(d.get("home")),
            workspace=_workspace(d.get("workspace")),
            presets=_presets(d.get("presets")),
            view_up=view_up,
            measurement_regions=tuple(regions),
            closure_names=tuple(closure_names),
            actuator_names=dict(actuator_names),
            readings=JointReadings.from_values(
                d.get("columns"), d.get("joint_units"), d.get("joint_reference"), "sidecar"
            ),
        )

    def replace(self, **changes: Any) -> Sidecar:
        """A copy with some fields changed (values re-checked through :meth:`from_dict`)."""
        d = self.to_dict()
        d.update(changes)
        return Sidecar.from_dict({k: v for k, v in d.items() if v is not None})

    def to_dict(self) -> dict[str, Any]:
        """YAML-safe mapping with only the keys that differ from the defaults."""
        out: dict[str, Any] = {}
        if self.closed_loop:
            out["closed_loop"] = [list(p) for p in self.closed_loop]
            out["type"] = [k if isinstance(k, str) else list(k) for k in self.type]
        if self.name_mot is not None:
            out["name_mot"] = list(self.name_mot)
        if self.joint_name:
            out["joint_name"] = list(self.joint_name)
            out["joint_type"] = list(self.joint_type)
        if self.measured_frame is not None:
            out["measured_frame"] = self.measured_frame
        if self.measured != "pose":
            out["measured"] = (
                self.measured if isinstance(self.measured, str) else list(self.measured)
            )
        if self.view_up is not None:
            out["view_up"] = self.view_up
        if self.home:
            out["home"] = {k: v[0] if len(v) == 1 else list(v) for k, v in self.home.items()}
        ws: dict[str, Any] = {}
        for part in ("pose", "joints"):
            ranges = getattr(self.workspace, part)
            if ranges:
                ws[part] = {k: list(v) for k, v in ranges.items()}
        if self.workspace.floor is not None:
            ws["floor"] = self.workspace.floor
        if ws:
            out["workspace"] = ws
        if self.presets:
            out["presets"] = {k: list(v) for k, v in self.presets.items()}
        if self.measurement_regions:
            out["measurement_regions"] = list(self.measurement_regions)
        if self.closure_names:
            out["closure_names"] = list(self.closure_names)
        if self.actuator_names:
            out["actuator_names"] = dict(self.actuator_names)
        out.update(self.readings.to_dict())
        return out


def validate_sidecar(sidecar: Any) -> Sidecar:
    """Check a parsed sidecar mapping: same as :meth:`Sidecar.from_dict`."""
    return Sidecar.from_dict(sidecar)
