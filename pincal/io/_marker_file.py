"""Marker tables: motion-capture or tracker exports with joint readings, read as they are.

A foreign delimited table (see :mod:`pincal.io._delimited`: ``,`` ``;`` or tab, ``#``
lines skipped, one title line) with one row per pose: a column per actuated joint,
named as the URDF joint (case-insensitive; a bracketed unit ``[deg]`` / ``[mm]`` is
honoured, else SI) and, among any number of other columns (further markers, time
stamps), the three position columns of the marker used, named by the
:class:`pincal.measure.MarkerSetup` (e.g. ``x1, y1, z1``) in its ``length_unit``. The
positions are in the instrument's frame; the rows become position-only
:class:`pincal.measure.Measurements` of the marker frame ``tool``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pincal.errors import ColumnError, MeasurementFormatError
from pincal.io._delimited import read_table
from pincal.io._units import (
    LENGTH_UNITS,
    actuator_read_factors,
    check_actuator_ranges,
    unit_factor,
)
from pincal.measure import MarkerSetup, Measurements
from pincal.model import Mechanism

__all__ = ["read_marker_table"]


def read_marker_table(path: str | Path, mech: Mechanism, setup: MarkerSetup) -> Measurements:
    """Marker positions [m] (instrument frame) and joint values [m, rad] of every row.

    Args:
        path: the table (never modified).
        mech: the chain of :func:`pincal.measure.marker_mechanism` (its actuated joints
            name the joint columns).
        setup: the marker columns and their unit.

    Returns:
        Position-only measurements of ``mech.measured_frame``, no declared noise.

    Raises:
        ColumnError: a joint or marker column is missing (the columns found are listed).
        MeasurementFormatError: no data rows, an unknown unit.
        BadValueError: a cell that is not a finite number (names the line and column).
    """
    table = read_table(path)
    name = table.name
    lf = unit_factor(LENGTH_UNITS, setup.length_unit, "length", name)
    cols = list(table.columns)

    def index(title: str, what: str) -> int:
        k = table.find(title, [title], {})
        if k is None:
            raise ColumnError(
                f"{name}: no {what} column {title!r}; columns are {cols}", missing=[title]
            )
        return k

    joints = [index(j, "joint") for j in mech.actuated]
    marker = [index(c, "marker") for c in setup.columns]
    if not table.rows:
        raise MeasurementFormatError(f"{name}: no data rows")
    data = np.array([[table.number(i, k) for k in joints + marker] for i in range(len(table.rows))])
    n = len(joints)
    factors = actuator_read_factors(mech, [table.unit(k) for k in joints], name)
    q_act = data[:, :n] / factors
    check_actuator_ranges(mech, q_act, name, [cols[k] for k in joints])
    positions = data[:, n:] / lf
    return Measurements(
        q_act, positions, None, ("x", "y", "z"), mech.measured_frame, tuple(mech.actuated)
    )
