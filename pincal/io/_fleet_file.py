"""The fleet file (``pincal fleet run``): one model, the units and their data files.

::

    model: stewart_6ups            # bundled name or model path (relative to this file)
    params: stewart42              # optional parameter preset
    units:
      - {id: SN-0001, data: SN-0001/measurements.csv}
      - {id: SN-0002, data: SN-0002/measurements.csv, date: 2026-11-30, site: Lyon}

Data paths are relative to the fleet file's directory. A unit id names its
calibration directory, so it is a plain file name (letters, digits, ``-``, ``_``,
``.``; not starting with a dot). Keys beyond ``id`` and ``data`` are kept as metadata.

A unit calibrated more than once (a recalibration in the field) appears once per
session, each with its own ``date:`` (a file-name text; ISO dates ``YYYY-MM-DD`` sort
in time): its sessions are calibrated into ``<id>@<date>`` and compared for drift.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from pincal._yaml import load_yaml
from pincal.errors import FleetFileError, clip

__all__ = ["Fleet", "FleetUnit", "fleet_text", "read_fleet"]

_ID = re.compile(r"^[A-Za-z0-9_-][A-Za-z0-9_.-]{0,99}$")
_TOP = {"model", "params", "units"}


@dataclass(frozen=True)
class FleetUnit:
    """One unit of a fleet.

    Attributes:
        id: the unit's id (its calibration directory's name).
        data: its measurement file (absolute, or as written when relative).
        meta: other keys of the unit (date, serial number, site, …) as texts.
        repeated: the id has more than one session in the fleet (each with its date).
    """

    id: str
    data: Path
    meta: Mapping[str, str] = field(default_factory=dict)
    repeated: bool = False

    @property
    def label(self) -> str:
        """The calibration's name: the id, or ``<id>@<date>`` for one of several sessions."""
        return f"{self.id}@{self.meta['date']}" if self.repeated else self.id


@dataclass(frozen=True)
class Fleet:
    """A fleet file as read.

    Attributes:
        model: the model (bundled name, or a path resolved against the file's directory).
        preset: the parameter preset, or None for the model's first.
        units: the units, in file order.
        path: the fleet file.
    """

    model: str
    preset: str | None
    units: tuple[FleetUnit, ...]
    path: Path


def read_fleet(path: str | Path) -> Fleet:
    """Read and check a fleet file (see the module doc).

    Args:
        path: the fleet YAML file.

    Returns:
        The :class:`Fleet`, data paths resolved against the file's directory.

    Raises:
        FleetFileError: unreadable, not a mapping, an unknown or missing key, a unit
            without id or data, an id that is not a file name, an id repeated without
            a distinct file-name ``date:`` per session, a data file that does not exist.
    """
    path = Path(path)
    doc = load_yaml(path, "fleet file", FleetFileError)
    where = f"fleet file {clip(str(path))}"
    if not isinstance(doc, dict):
        raise FleetFileError(
            f"{where} must be a mapping with model: and units:, e.g. "
            "'model: stewart_6ups' and 'units: [{id: SN-0001, data: m.csv}]'"
        )
    unknown = sorted(set(map(str, doc)) - _TOP)
    if unknown:
        raise FleetFileError(f"{where}: unknown key(s) {unknown}; valid: {sorted(_TOP)}")
    model = doc.get("model")
    if not isinstance(model, str) or not model.strip():
        raise FleetFileError(f"{where}: give model: (a bundled name or a model path)")
    base = path.parent
    if (base / model).exists():
        model = str((base / model).resolve())
    preset = doc.get("params")
    if preset is not None and not isinstance(preset, str):
        raise FleetFileError(f"{where}: params: is a preset name, got {clip(preset)}")
    units = doc.get("units")
    if not isinstance(units, list) or not units:
        raise FleetFileError(f"{where}: units: must be a non-empty list of {{id:, data:}}")
    out: list[FleetUnit] = []
    for k, unit in enumerate(units, start=1):
        if not isinstance(unit, dict) or "id" not in unit or "data" not in unit:
            raise FleetFileError(
                f"{where}: unit {k} must be a mapping with id: and data:, got {clip(unit)}"
            )
        uid = str(unit["id"])
        if not _ID.match(uid):
            raise FleetFileError(
                f"{where}: unit {k} id {clip(uid, quote=True)} names its calibration "
                "directory: use letters, digits, '-', '_', '.' (not starting with '.')"
            )
        data = base / str(unit["data"])
        if not data.is_file():
            raise FleetFileError(
                f"{where}: unit {uid}: data file {clip(str(data))} does not exist (data paths "
                "are relative to the fleet file's directory)"
            )
        meta = {str(key): str(v) for key, v in unit.items() if key not in ("id", "data")}
        out.append(FleetUnit(uid, data, meta))
    return Fleet(model, preset, _sessions(out, where), path)


def _sessions(units: list[FleetUnit], where: str) -> tuple[FleetUnit, ...]:
    """Mark the units whose id appears more than once; check their dates name them."""
    count: dict[str, int] = {}
    for u in units:
        count[u.id] = count.get(u.id, 0) + 1
    labels: set[str] = set()
    out = []
    for u in units:
        if count[u.id] == 1:
            out.append(u)
            continue
        date = u.meta.get("date")
        if date is None or not _ID.match(date) or f"{u.id}@{date}" in labels:
            raise FleetFileError(
                f"{where}: unit id {clip(u.id, quote=True)} appears {count[u.id]} times: a unit "
                f"calibrated again needs a distinct date: per session (e.g. date: 2026-11-30), "
                f"got {clip(date, quote=True) if date else 'none'}; otherwise give each unit "
                f"its own id"
            )
        labels.add(f"{u.id}@{date}")
        out.append(FleetUnit(u.id, u.data, u.meta, repeated=True))
    return tuple(out)


def fleet_text(model: str, units: list[dict[str, Any]], preset: str | None = None) -> str:
    """The YAML text of a fleet file (written by ``pincal fleet simulate``).

    Args:
        model: the model name or path.
        units: ``[{id, data, …}]`` with data paths relative to the file's directory.
        preset: the parameter preset, or None.

    Returns:
        The text, one unit per line.
    """
    head: dict[str, Any] = {"model": model} | ({"params": preset} if preset else {})
    lines = [yaml.safe_dump(head, sort_keys=False).rstrip(), "units:"]
    for unit in units:
        flow = yaml.safe_dump(unit, default_flow_style=True, sort_keys=False, width=1000)
        lines.append(f"  - {flow.strip()}")
    return "\n".join(lines) + "\n"
