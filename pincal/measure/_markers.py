"""Markers on a link, seen in an unknown instrument frame (motion capture, trackers).

A motion-capture system or a tracker reports marker positions in its own frame; the
marker sits at a point of a named link of the robot. Both are constant unknowns of the
calibration:

* the **instrument frame** — the robot base in the instrument frame, the ``base_frame``
  joint origin of :func:`pincal.model.serial_mechanism` (6 parameters);
* the **marker offset** — the marker in the measured link's frame, the translation of
  the ``tool_frame`` joint origin (3 parameters ``tool_frame.tx/ty/tz``; a point has no
  orientation). A *marker body* whose orientation is measured too (orientation
  columns, :mod:`pincal.measure._orientation`) is a full frame on the link: the whole
  ``tool_frame`` origin (6 parameters) is unknown, and the marker mechanism measures
  the pose.

:class:`MarkerSetup` declares them (and the locked joints); :func:`marker_mechanism`
builds the chain; :func:`pincal.measure.register_markers`
(:mod:`pincal.measure._marker_registration`) solves both in closed form before any
identification, which then refines both jointly with the robot's own parameters.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

from pincal.errors import MeasurementError, MobilityError, ModelFileError, UnknownNameError
from pincal.measure._orientation import check_orientation
from pincal.model import (
    BASE_JOINT,
    MOVABLE_TYPES,
    TOOL_JOINT,
    Mechanism,
    UrdfTree,
    chain_joints,
    chain_preset,
    load_mechanism,
    resolve_named,
    serial_mechanism,
)

__all__ = ["MarkerSetup", "marker_frame", "marker_mechanism", "marker_mechanisms"]

FRAME_CHOICES = ("unknown", "known")


@dataclass(frozen=True)
class MarkerSetup:
    """How marker positions relate to the robot.

    Attributes:
        link: the measured link (the marker is fixed on it).
        instrument_frame: ``"unknown"`` (registered, then identified) or ``"known"``
            (the instrument frame is the robot's base frame: held at identity).
        marker: the marker in ``link``'s frame [m], or None when unknown.
        marker_std: 1σ of a given ``marker`` [m] (a prior); None with a given marker
            holds it exactly.
        lock: joints made fixed ``{name: value}`` [m, rad]; every other movable joint
            off the chain to ``link`` is locked at 0.
        columns: the marker's three position columns (x, y, z) in the file.
        length_unit: unit of the marker columns (``m``, ``mm``, ``um``).
        more_columns: the columns of further distinct markers, each with its own
            unknown offset (joint ``marker<k>_frame``, k = 2, 3, …) and the same
            instrument frame; fitted together with the first.
        more_links: the link of each further marker (one per ``more_columns`` entry),
            or () when all are on ``link``. Markers on several links make one problem
            of several chains from ``root`` sharing the links they have in common (two
            arms and the torso): every joint on a chain to one of the links is
            calibrated.
        orientation_columns: the columns of the body's orientation (a single marker
            body: no ``more_columns``), or () for a point.
        orientation: their convention (:data:`pincal.measure.ORIENTATIONS`, e.g.
            ``rpy-deg``), with ``orientation_columns`` only.
        root: the link the measured chain starts from (fixed to the instrument: a
            humanoid's sole, a mobile manipulator's torso), or None for the URDF's root;
            the tree is re-rooted there (:func:`pincal.model.reroot_urdf`) and the joints
            between ``root`` and ``link`` are the chain.
    """

    link: str
    instrument_frame: str = "unknown"
    marker: tuple[float, float, float] | None = None
    marker_std: float | None = None
    lock: Mapping[str, float] = field(default_factory=dict)
    columns: tuple[str, str, str] = ("x", "y", "z")
    length_unit: str = "m"
    more_columns: tuple[tuple[str, str, str], ...] = ()
    more_links: tuple[str, ...] = ()
    orientation_columns: tuple[str, ...] = ()
    orientation: str | None = None
    root: str | None = None

    def __post_init__(self) -> None:
        if self.instrument_frame not in FRAME_CHOICES:
            raise MeasurementError(
                f"instrument frame {self.instrument_frame!r} is not valid; use one of "
                f"{', '.join(FRAME_CHOICES)}"
            )
        if len(self.columns) != 3 or len(set(self.columns)) != 3:
            raise MeasurementError(
                f"marker columns must be three distinct names (x, y, z), got {list(self.columns)}"
            )
        if self.marker is not None:
            v = np.asarray(self.marker, dtype=float)
            if v.shape != (3,) or not np.all(np.isfinite(v)):
                raise MeasurementError(f"marker must be 3 finite numbers [m], got {self.marker}")
            object.__setattr__(self, "marker", tuple(float(x) for x in v))
        elif self.marker_std is not None:
            raise MeasurementError("marker_std applies to a given marker only")
        if self.marker_std is not None and not (
            np.isfinite(self.marker_std) and self.marker_std > 0
        ):
            raise MeasurementError(f"marker_std must be > 0 [m], got {self.marker_std}")
        object.__setattr__(self, "lock", {str(k): float(v) for k, v in self.lock.items()})
        object.__setattr__(self, "columns", tuple(str(c) for c in self.columns))
        more = tuple(tuple(str(c) for c in cols) for cols in self.more_columns)
        object.__setattr__(self, "more_columns", more)
        for cols in more:
            if len(cols) != 3 or len(set(cols)) != 3:
                raise MeasurementError(
                    f"marker columns must be three distinct names (x, y, z), got {list(cols)}"
                )
        object.__setattr__(self, "more_links", tuple(str(v) for v in self.more_links))
        if self.more_links and len(self.more_links) != len(more):
            raise MeasurementError(
                f"{len(self.more_links)} links for {len(more)} further markers: give one link "
                "per further marker's columns, or none when all are on the first marker's link"
            )
        sets = self.marker_sets
        if len(set(sets)) != len(sets):
            raise MeasurementError(f"a marker is named twice: {[list(c) for c in sets]}")
        if more and self.marker is not None:
            raise MeasurementError(
                "a given marker offset applies to a single marker; with several markers "
                "every offset is unknown (registered, then identified)"
            )
        self._check_orientation()

    def _check_orientation(self) -> None:
        cols = tuple(str(c) for c in self.orientation_columns)
        object.__setattr__(self, "orientation_columns", cols)
        if not cols and self.orientation is None:
            return
        if not cols or self.orientation is None:
            raise MeasurementError(
                "give the orientation columns together with their convention (e.g. "
                "columns r,p,y with orientation rpy-deg)"
            )
        check_orientation(self.orientation, cols)
        if self.more_columns:
            raise MeasurementError(
                "orientation columns describe one marker body; give a single set of "
                "marker columns with them"
            )
        shared = sorted(set(cols) & set(self.columns))
        if shared:
            raise MeasurementError(
                f"columns {shared} are named as position and as orientation columns; name "
                "each column once, as titled in the table (e.g. position x,y,z and "
                "orientation roll,pitch,yaw)"
            )

    @property
    def measures_orientation(self) -> bool:
        """True for a marker body whose orientation is read (a 6-D marker)."""
        return bool(self.orientation_columns)

    @property
    def marker_sets(self) -> tuple[tuple[str, str, str], ...]:
        """The columns of every marker used, the first one first."""
        return (self.columns, *self.more_columns)  # type: ignore[return-value]

    @property
    def marker_links(self) -> tuple[str, ...]:
        """The link of every marker used, the first one's first."""
        return (self.link, *(self.more_links or (self.link,) * len(self.more_columns)))

    @property
    def held(self) -> tuple[str, ...]:
        """Registration parameters held at their start values (not identified)."""
        base = [f"{BASE_JOINT}.{d}" for d in ("tx", "ty", "tz", "rx", "ry", "rz")]
        tool = [f"{TOOL_JOINT}.{d}" for d in ("tx", "ty", "tz")]
        held = base if self.instrument_frame == "known" else []
        return tuple(held + (tool if self.marker is not None and self.marker_std is None else []))

    def to_dict(self) -> dict[str, Any]:
        """Plain data (for the calibration manifest); :meth:`from_dict` reads it back."""
        return {
            "link": self.link,
            "instrument_frame": self.instrument_frame,
            "marker": list(self.marker) if self.marker is not None else None,
            "marker_std": self.marker_std,
            "lock": dict(self.lock),
            "columns": list(self.columns),
            "length_unit": self.length_unit,
            "more_columns": [list(c) for c in self.more_columns],
            **({"more_links": list(self.more_links)} if self.more_links else {}),
            **(
                {"orientation_columns": list(self.orientation_columns),
                 "orientation": self.orientation}
                if self.measures_orientation else {}
            ),
            **({"root": self.root} if self.root is not None else {}),
        }  # fmt: skip

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> MarkerSetup:
        """The setup from its JSON form (as written by ``to_dict``)."""
        m = d.get("marker")
        return cls(
            link=str(d["link"]),
            instrument_frame=str(d.get("instrument_frame", "unknown")),
            marker=tuple(m) if m is not None else None,  # type: ignore[arg-type]
            marker_std=d.get("marker_std"),
            lock=dict(d.get("lock") or {}),
            columns=tuple(d.get("columns") or ("x", "y", "z")),  # type: ignore[arg-type]
            length_unit=str(d.get("length_unit", "m")),
            more_columns=tuple(tuple(c) for c in d.get("more_columns") or ()),  # type: ignore[misc]
            more_links=tuple(d.get("more_links") or ()),
            orientation_columns=tuple(d.get("orientation_columns") or ()),
            orientation=d.get("orientation"),
            root=d.get("root"),
        )


def _off_chain_locks(
    model: str, links: Sequence[str], lock: Mapping[str, float], root: str | None = None
) -> dict[str, float]:
    """``lock`` plus every movable joint off the chains from ``root`` to ``links`` at 0."""
    from pincal._files import read_text

    urdf = resolve_named(model).urdf  # a name, a path, or a local sidecar with `robot:`
    tree = UrdfTree(read_text(urdf, "URDF", error=ModelFileError))
    for name in (*links, root or tree.root_link):
        if name not in tree.links:
            raise UnknownNameError("link", name, list(tree.links))
    chain = {j for link in links for j in chain_joints(tree, root or tree.root_link, link)}
    out = {n: 0.0 for n, j in tree.joints.items() if j.type in MOVABLE_TYPES and n not in chain}
    bad = sorted(set(lock) - set(tree.joints))
    if bad:
        raise UnknownNameError("joint", bad[0], list(tree.joints))
    return {**out, **lock}


def marker_frame(k: int) -> tuple[str, str]:
    """(joint, link) of marker k (0-based): ``tool_frame``/``tool``, then ``marker<k+1>_frame``."""
    return (TOOL_JOINT, "tool") if k == 0 else (f"marker{k + 1}_frame", f"marker{k + 1}")


def marker_mechanism(model: str, setup: MarkerSetup) -> Mechanism:
    """The chain from the instrument to the marker: ``serial_mechanism`` measuring a point.

    A marker body with orientation columns measures the pose (the ``tool_frame``
    origin's six parameters join the presets).

    Joints off the chain to ``setup.link`` (a mobile base's wheels, a head, a hand) are
    locked, and so are ``setup.lock``. With ``setup.root`` the chain starts at that link
    (the tree re-rooted there, :func:`pincal.model.reroot_urdf`). The measured frame is
    ``tool`` (the marker); ``base_frame`` and ``tool_frame`` start at identity, or at the
    given marker. With further markers (``setup.more_columns``), fixed joints
    ``marker<k>_frame`` from each marker's link to links ``marker<k>`` (start: identity)
    are added, and their ``tx ty tz`` join the ``chain`` and ``base_tool`` presets; with
    markers on several links (``setup.more_links``) every joint on a chain to one of
    them is commanded and in ``chain`` (the shared ones once).

    Home is the model's home as :func:`pincal.model.load_mechanism` (and ``pincal info
    MODEL --frame LINK``) has it: the sidecar's, the SRDF's, else the searched regular
    one — one home for every route (a table's ``joint_reference: home`` is relative to
    it).

    Raises:
        UnknownNameError: unknown link or locked joint; ModelFileError: the URDF;
        MobilityError: no joint moves the marker (the link is the root or every joint
            on the way is locked).
    """
    lock = _off_chain_locks(model, setup.marker_links, setup.lock, setup.root)
    marker = pin.SE3(np.eye(3), np.asarray(setup.marker)) if setup.marker is not None else None
    measured = "pose" if setup.measures_orientation else "position"
    mech = serial_mechanism(
        model, flange=setup.link, lock=lock, measured=measured, T_flange_tool=marker,
        root=setup.root,
    )
    if not mech.actuated:
        start = "the robot's root" if setup.root is None else f"the chain's start {setup.root!r}"
        raise MobilityError(
            f"nothing moves the marker: no unlocked joint between {start} and link "
            f"{setup.link!r} (locked: {', '.join(sorted(setup.lock)) or 'none'}); give the "
            "link the marker is on, further along the chain, or lock fewer joints"
        )
    off_chain = {k: v for k, v in lock.items() if k not in setup.lock}
    mech = _with_model_home(model, setup.link, off_chain, mech)
    if not setup.more_columns:
        return mech
    import xml.etree.ElementTree as ET

    root = ET.fromstring(mech.urdf_xml)
    frames: list[dict[str, object]] = []  # the further markers' offsets
    for k in range(1, len(setup.marker_sets)):
        joint, link = marker_frame(k)
        if joint in mech.tree.joints or link in mech.tree.links:
            raise ModelFileError(f"cannot add marker {k + 1}: the URDF already has {joint!r}")
        root.append(ET.Element("link", {"name": link}))
        e = ET.SubElement(root, "joint", {"name": joint, "type": "fixed"})
        ET.SubElement(e, "parent", {"link": setup.marker_links[k]})
        ET.SubElement(e, "child", {"link": link})
        ET.SubElement(e, "origin", {"xyz": "0 0 0", "rpy": "0 0 0"})
        frames.append({"joints": joint, "dofs": ["tx", "ty", "tz"]})
    sidecar = mech.sidecar.to_dict()
    presets = dict(sidecar.get("presets") or {})
    chained = {e["joints"] for e in presets["chain"]}
    others = []  # the other chains' joints (the shared ones are in the first chain's)
    for other in dict.fromkeys(setup.marker_links[1:]):
        for entry in chain_preset(mech, base=False, tool=False, frame=other):
            if entry["joints"] not in chained:
                chained.add(entry["joints"])
                others.append(entry)
    presets["chain"] = [*presets["chain"], *frames, *others]
    presets["base_tool"] = [*presets["base_tool"], *frames]
    sidecar["presets"] = presets
    if len(set(setup.marker_links)) > 1:  # every chain's joints are commanded
        on = {str(e["joints"]) for e in presets["chain"]}
        sidecar["name_mot"] = [n for n in mech.model.names[1:] if n in on]
    return Mechanism(
        ET.tostring(root, encoding="unicode"), sidecar, name=mech.name, source=mech.source
    )


def _with_model_home(model: str, link: str, lock: Mapping[str, float],
                     mech: Mechanism) -> Mechanism:  # fmt: skip
    """``mech`` with the home :func:`pincal.model.load_mechanism` searches (if it does).

    A robot by name without SRDF pose or sidecar ``home`` gets a searched regular home
    when loaded (regular for the measured frame: here ``link``, as ``pincal info MODEL
    --frame LINK`` prints it); the marker chain is built without that search, so it
    takes the loaded model's values of its own joints. The model is loaded with the
    joints off the chain locked (``lock``: they do not move the link, so the home is the
    same, found ten times faster on a 50-joint TIAGo); joints the user locks on the
    chain stay free there, so a lock does not move the home of the others.
    """
    if mech.sidecar.to_dict().get("home"):  # the sidecar's or the SRDF's: no search
        return mech
    full = load_mechanism(model, link, lock=lock)
    side = full.sidecar.to_dict().get("home")
    if not isinstance(side, Mapping):
        return mech
    home = {j: float(side[j]) for j in mech.actuated if j in side}
    if not home:
        return mech
    sidecar = mech.sidecar.to_dict()
    sidecar["home"] = home
    return Mechanism(mech.urdf_xml, sidecar, name=mech.name, source=mech.source)


def marker_mechanisms(mech: Mechanism, setup: MarkerSetup) -> tuple[Mechanism, ...]:
    """One mechanism per marker: ``mech`` measuring marker k's link (k = 1 is ``mech``)."""
    out = [mech]
    for k in range(1, len(setup.marker_sets)):
        out.append(
            Mechanism(
                mech.urdf_xml,
                mech.sidecar,
                name=mech.name,
                source=mech.source,
                measured_frame=marker_frame(k)[1],
                q_guess=mech.q_home,
                options=mech.options,
            )
        )
    return tuple(out)
