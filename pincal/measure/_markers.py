"""Markers on a link, seen in an unknown instrument frame (motion capture, trackers).

A motion-capture system or a tracker reports marker positions in its own frame; the
marker sits at a point of a named link of the robot. Both are constant unknowns of the
calibration:

* the **instrument frame** — the robot base in the instrument frame, the ``base_frame``
  joint origin of :func:`pincal.model.serial_mechanism` (6 parameters);
* the **marker offset** — the marker in the measured link's frame, the translation of
  the ``tool_frame`` joint origin (3 parameters ``tool_frame.tx/ty/tz``; a point has no
  orientation).

:class:`MarkerSetup` declares them (and the locked joints); :func:`marker_mechanism`
builds the chain; :func:`register_markers` solves both in closed form before any
identification: with the marker fixed, the base is a best-fit rigid transform
(Kabsch); with the base fixed, the marker is linear least squares; the two alternate
until the marker moves less than 1 nm. Identification then refines both jointly with
the robot's own parameters.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

from pincal.errors import MeasurementError, ModelFileError, UnknownNameError
from pincal.measure._measurements import Measurements
from pincal.measure._tracker import RigidFit, fit_rigid_transform
from pincal.model import (
    BASE_JOINT,
    MOVABLE_TYPES,
    TOOL_JOINT,
    Mechanism,
    UrdfTree,
    resolve_named,
    serial_mechanism,
    with_joint_origin,
)

__all__ = [
    "MarkerRegistration",
    "MarkerSetup",
    "marker_frame",
    "marker_mechanism",
    "marker_mechanisms",
    "register_markers",
]

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
        more_columns: the columns of further distinct markers on the same link, each
            with its own unknown offset (joint ``marker<k>_frame``, k = 2, 3, …) and the
            same instrument frame; fitted together with the first.
    """

    link: str
    instrument_frame: str = "unknown"
    marker: tuple[float, float, float] | None = None
    marker_std: float | None = None
    lock: Mapping[str, float] = field(default_factory=dict)
    columns: tuple[str, str, str] = ("x", "y", "z")
    length_unit: str = "m"
    more_columns: tuple[tuple[str, str, str], ...] = ()

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
        sets = self.marker_sets
        if len(set(sets)) != len(sets):
            raise MeasurementError(f"a marker is named twice: {[list(c) for c in sets]}")
        if more and self.marker is not None:
            raise MeasurementError(
                "a given marker offset applies to a single marker; with several markers "
                "every offset is unknown (registered, then identified)"
            )

    @property
    def marker_sets(self) -> tuple[tuple[str, str, str], ...]:
        """The columns of every marker used, the first one first."""
        return (self.columns, *self.more_columns)  # type: ignore[return-value]

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
        }

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> MarkerSetup:
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
        )


def _off_chain_locks(model: str, link: str, lock: Mapping[str, float]) -> dict[str, float]:
    """``lock`` plus every movable joint off the chain to ``link`` at 0."""
    from pincal._files import read_text

    urdf = resolve_named(model).urdf  # a name, a path, or a local sidecar with `robot:`
    tree = UrdfTree(read_text(urdf, "URDF", error=ModelFileError))
    if link not in tree.links:
        raise UnknownNameError("link", link, list(tree.links))
    chain = set(tree.ancestors(link))
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

    Joints off the chain to ``setup.link`` (a mobile base's wheels, a head, a hand) are
    locked, and so are ``setup.lock``. The measured frame is ``tool`` (the marker);
    ``base_frame`` and ``tool_frame`` start at identity, or at the given marker. With
    further markers (``setup.more_columns``), fixed joints ``marker<k>_frame`` from the
    link to links ``marker<k>`` (start: identity) are added, and their ``tx ty tz``
    join the ``chain`` and ``base_tool`` presets.

    Raises:
        UnknownNameError: unknown link or locked joint; ModelFileError: the URDF.
    """
    lock = _off_chain_locks(model, setup.link, setup.lock)
    marker = pin.SE3(np.eye(3), np.asarray(setup.marker)) if setup.marker is not None else None
    mech = serial_mechanism(
        model, flange=setup.link, lock=lock, measured="position", T_flange_tool=marker
    )
    if not setup.more_columns:
        return mech
    import xml.etree.ElementTree as ET

    root = ET.fromstring(mech.urdf_xml)
    extra = []
    for k in range(1, len(setup.marker_sets)):
        joint, link = marker_frame(k)
        if joint in mech.tree.joints or link in mech.tree.links:
            raise ModelFileError(f"cannot add marker {k + 1}: the URDF already has {joint!r}")
        root.append(ET.Element("link", {"name": link}))
        e = ET.SubElement(root, "joint", {"name": joint, "type": "fixed"})
        ET.SubElement(e, "parent", {"link": setup.link})
        ET.SubElement(e, "child", {"link": link})
        ET.SubElement(e, "origin", {"xyz": "0 0 0", "rpy": "0 0 0"})
        extra.append({"joints": joint, "dofs": ["tx", "ty", "tz"]})
    sidecar = mech.sidecar.to_dict()
    presets = dict(sidecar.get("presets") or {})
    for name in ("chain", "base_tool"):
        presets[name] = [*presets[name], *extra]
    sidecar["presets"] = presets
    return Mechanism(
        ET.tostring(root, encoding="unicode"), sidecar, name=mech.name, source=mech.source
    )


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


@dataclass(frozen=True)
class MarkerRegistration:
    """Closed-form registration of the instrument frame and the marker offset.

    Attributes:
        T_instrument_base: robot base in the instrument frame.
        marker: marker in the measured link's frame [m].
        fit: the final rigid fit (``fit.rms`` [m] is what identification starts from).
        iterations: alternations used.
        mechanism: the input mechanism with ``base_frame`` and ``tool_frame`` set (and
            ``marker<k>_frame`` of further markers).
        more_markers: further markers in the link's frame [m] (k = 2, 3, …).
    """

    T_instrument_base: pin.SE3
    marker: np.ndarray
    fit: RigidFit
    iterations: int
    mechanism: Mechanism
    more_markers: tuple[np.ndarray, ...] = ()


def register_markers(
    mech: Mechanism,
    measurements: Measurements,
    marker_known: bool = False,
    frame_known: bool = False,
    max_iterations: int = 500,
    more: tuple[Measurements, ...] = (),
) -> MarkerRegistration:
    """Instrument frame and marker offset in closed form (alternating Kabsch / least squares).

    Args:
        mech: from :func:`marker_mechanism` (``base_frame`` and ``tool_frame`` joints).
        measurements: marker positions [m] in the instrument frame, ≥ 3 poses.
        marker_known: keep the mechanism's ``tool_frame`` translation.
        frame_known: keep the mechanism's ``base_frame``.
        max_iterations: alternation limit.
        more: positions of further markers on the same link, rows as ``measurements``
            (their offsets are unknown; all markers share the rigid fit).

    Raises:
        MeasurementError: too few poses, or collinear predicted points.
    """
    joints = [BASE_JOINT, TOOL_JOINT] + [marker_frame(k)[0] for k in range(1, len(more) + 1)]
    for j in joints:
        if j not in mech.tree.joints:
            raise ModelFileError(f"marker registration needs the {j!r} joint (marker_mechanism)")
    if len(measurements) < 3:
        raise MeasurementError(f"registration needs at least 3 poses, got {len(measurements)}")
    T_base = mech.tree.joints[BASE_JOINT].origin
    T_tool = mech.tree.joints[TOOL_JOINT].origin
    bare = with_joint_origin(
        with_joint_origin(mech, BASE_JOINT, pin.SE3.Identity()), TOOL_JOINT, pin.SE3.Identity()
    )
    flange = [bare.frame_placement(q) for q in bare.configurations(measurements.q_act)]
    R_f = np.array([T.rotation for T in flange])  # (m, 3, 3) link in robot base
    t_f = np.array([T.translation for T in flange])
    P = [measurements.positions, *(m.positions for m in more)]
    mk = [np.asarray(T_tool.translation, dtype=float).copy()]
    mk += [np.zeros(3) for _ in more]
    T = T_base
    it = 0
    while it < max_iterations:
        it += 1
        pred = [t_f + np.einsum("mij,j->mi", R_f, v) for v in mk]
        fit = None if frame_known else fit_rigid_transform(np.vstack(pred), np.vstack(P))
        T = T_base if fit is None else fit.T
        A = np.einsum("ij,mjk->mik", T.rotation, R_f).reshape(-1, 3)
        moved = 0.0
        for k, Pk in enumerate(P):
            if k == 0 and marker_known:
                continue
            b = (Pk - t_f @ T.rotation.T - T.translation).reshape(-1)
            new = np.linalg.lstsq(A, b, rcond=None)[0]
            moved = max(moved, float(np.linalg.norm(new - mk[k])))
            mk[k] = new
        if moved < 1e-9 or frame_known or (marker_known and not more):
            break
    stacked = np.vstack([t_f + np.einsum("mij,j->mi", R_f, v) for v in mk])
    res = np.vstack(P) - (stacked @ T.rotation.T + T.translation)  # every marker's rows
    dist = np.linalg.norm(res, axis=1)
    fit = RigidFit(T, res, dist, float(np.sqrt(np.mean(dist**2))))
    out = with_joint_origin(mech, BASE_JOINT, T)
    out = with_joint_origin(out, TOOL_JOINT, pin.SE3(T_tool.rotation, mk[0]))
    for k in range(1, len(mk)):
        out = with_joint_origin(out, marker_frame(k)[0], pin.SE3(np.eye(3), mk[k]))
    return MarkerRegistration(T, mk[0], fit, it, out, tuple(mk[1:]))
