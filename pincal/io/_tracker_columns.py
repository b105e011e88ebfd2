"""Columns of the tracker import's tables: finding them by title and reading them in SI.

The field aliases, the length unit of point coordinates (stated or bracketed in the
titles) and the controller log's actuator columns; the matching of points to log rows
is :mod:`pincal.io._import_tracker`.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from pincal._yaml import shown
from pincal.errors import ColumnError, MeasurementError
from pincal.io._delimited import Table
from pincal.io._units import ANGLE_UNITS, LENGTH_UNITS, check_actuator_ranges, unit_factor
from pincal.model import Mechanism

__all__ = ["ALIASES", "length_factor", "read_actuators", "read_xyz"]

ALIASES = {
    "pose": ("pose", "group", "pose_id", "group_id", "pose id", "group id"),
    "time": ("time", "timestamp", "t", "time_s"),
    "point": ("point", "name", "target", "point_name", "point name"),
    "x": ("x",),
    "y": ("y",),
    "z": ("z",),
}
"""Recognised column titles (case ignored) of each field."""


def length_factor(table: Table, cols: list[int], unit: str | None) -> float:
    """Factor from the table's coordinate unit to metres (titles' ``[unit]`` or the stated one)."""
    units = {u for k in cols if (u := table.unit(k)) is not None}
    if len(units) > 1 or (units and unit is not None and units != {unit}):
        raise MeasurementError(
            f"{table.name}: coordinate units disagree ({sorted(units)} in the titles, "
            f"{shown(unit)} stated); state one unit"
        )
    chosen = next(iter(units), unit)
    if chosen is None:
        raise MeasurementError(
            f"{table.name}: the length unit of {[table.columns[k] for k in cols]} is unknown; "
            f"state it (--unit mm) or write it in the titles ('X [mm]'); units: "
            f"{', '.join(LENGTH_UNITS)}"
        )
    return unit_factor(LENGTH_UNITS, chosen, "length", table.name)


def read_xyz(
    table: Table, mapping: Mapping[str, str], unit: str | None, what: str
) -> tuple[list[str], np.ndarray, float]:
    """(point names, (rows, 3) points [m], the unit's factor from metres) of a points table."""
    found = {f: table.find(f, ALIASES[f], mapping) for f in ("point", "x", "y", "z")}
    missing = [f for f, k in found.items() if k is None]
    if missing:
        raise ColumnError(
            f"{table.name}: no {missing} column in the {what} (columns "
            f"{shown(list(table.columns))}); "
            f"map them, e.g. --columns point=Name,x=X",
            missing=missing,
        )
    cols = {f: k for f, k in found.items() if k is not None}
    xyz = [cols["x"], cols["y"], cols["z"]]
    lf = length_factor(table, xyz, unit)
    names = [table.text(i, cols["point"]) for i in range(len(table.rows))]
    pts = np.array([[table.number(i, k) / lf for k in xyz] for i in range(len(table.rows))])
    return names, pts.reshape(-1, 3), lf


def read_actuators(
    log: Table,
    mech: Mechanism,
    log_columns: Mapping[str, str],
    length_unit: str,
    angle_unit: str,
) -> np.ndarray:
    """(rows, n_act) actuator values [m, rad] of the controller log, checked against the ranges."""
    unknown = set(log_columns) - set(mech.actuated) - {"pose", "time"}
    if unknown:
        raise ColumnError(
            f"{log.name}: mapped fields {sorted(unknown)} are not actuated joints of "
            f"{mech.name!r} ({list(mech.actuated)}) nor pose/time",
            unknown=sorted(unknown),
        )
    cols, factors = [], []
    for joint in mech.actuated:
        k = log.find(joint, (joint,), log_columns)
        if k is None:
            raise ColumnError(
                f"{log.name}: no column for actuated joint {joint!r} (columns "
                f"{shown(list(log.columns))}); map it, e.g. --log-columns {joint}=Axis1",
                missing=[joint],
            )
        revolute = mech.tree.joints[joint].type in ("revolute", "continuous")
        table = ANGLE_UNITS if revolute else LENGTH_UNITS
        unit = log.unit(k) or (angle_unit if revolute else length_unit)
        cols.append(k)
        factors.append(unit_factor(table, unit, "angle" if revolute else "length", log.name))
    q = np.array([[log.number(i, k) for k in cols] for i in range(len(log.rows))])
    q = q.reshape(-1, len(cols)) / np.array(factors)
    check_actuator_ranges(mech, q, log.name, [log.columns[k] for k in cols], log.lines)
    return q
