"""Marker tables: motion-capture or tracker exports with joint readings, read as they are.

A foreign delimited table (see :mod:`pincal.io._delimited`: ``,`` ``;`` or tab, ``#``
lines skipped, one title line) with one row per pose: a column per actuated joint,
named as the URDF joint (case-insensitive; a bracketed unit ``[deg]`` / ``[mm]`` is
honoured, else SI) and, among any number of other columns (further markers, time
stamps), the three position columns of the marker(s) used, named by the
:class:`pincal.measure.MarkerSetup` (e.g. ``x1, y1, z1``; further markers in its
``more_columns``) in its ``length_unit``. The positions are in the instrument's frame;
the rows become position-only :class:`pincal.measure.Measurements` of the marker
frame ``tool`` (further markers: ``marker2``, ``marker3``, …, one set each).

Exports often repeat one marker under two names (the same values in two column
triples); :func:`distinct_markers` finds such copies among the markers chosen and keeps
one, saying so — a copy fitted as a second marker would count every point twice.
"""

from __future__ import annotations

from dataclasses import replace
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
from pincal.measure import MarkerSetup, Measurements, marker_frame
from pincal.model import Mechanism

__all__ = ["distinct_markers", "read_marker_sets", "read_marker_table"]


def read_marker_table(path: str | Path, mech: Mechanism, setup: MarkerSetup) -> Measurements:
    """The first marker's rows of :func:`read_marker_sets` (see there)."""
    return read_marker_sets(path, mech, setup)[0]


def distinct_markers(path: str | Path, setup: MarkerSetup) -> tuple[MarkerSetup, tuple[str, ...]]:
    """``setup`` without markers whose columns repeat an earlier marker's, value for value.

    Returns:
        (the setup with its copies left out, a sentence per copy left out).

    Raises:
        ColumnError, MeasurementFormatError, BadValueError: as :func:`read_marker_sets`.
    """
    if not setup.more_columns:
        return setup, ()
    table = read_table(path)
    cols = list(table.columns)
    values = []
    for triple in setup.marker_sets:
        idx = []
        for c in triple:
            k = table.find(c, [c], {})
            if k is None:
                raise ColumnError(
                    f"{table.name}: no marker column {c!r}; columns are {cols}", missing=[c]
                )
            idx.append(k)
        values.append(
            np.array([[table.number(i, k) for k in idx] for i in range(len(table.rows))])
        )
    keep: list[int] = []
    notes = []
    for k, v in enumerate(values):
        same = next((j for j in keep if np.array_equal(values[j], v)), None)
        if same is None:
            keep.append(k)
            continue
        a, b = setup.marker_sets[k], setup.marker_sets[same]
        notes.append(
            f"{table.name}: columns {','.join(a)} repeat {','.join(b)} value for value (one "
            f"marker exported twice): used once, as {','.join(b)}"
        )
    sets = [setup.marker_sets[k] for k in keep]
    return replace(setup, columns=sets[0], more_columns=tuple(sets[1:])), tuple(notes)


def read_marker_sets(
    path: str | Path, mech: Mechanism, setup: MarkerSetup
) -> tuple[Measurements, ...]:
    """Marker positions [m] (instrument frame) and joint values [m, rad] of every row.

    Args:
        path: the table (never modified).
        mech: the chain of :func:`pincal.measure.marker_mechanism` (its actuated joints
            name the joint columns).
        setup: the marker columns and their unit.

    Returns:
        Per marker of ``setup.marker_sets``, position-only measurements (same rows) of
        its frame (:func:`pincal.measure.marker_frame`: ``mech.measured_frame`` for the
        first), no declared noise.

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
    marker = [index(c, "marker") for triple in setup.marker_sets for c in triple]
    if not table.rows:
        raise MeasurementFormatError(f"{name}: no data rows")
    data = np.array([[table.number(i, k) for k in joints + marker] for i in range(len(table.rows))])
    n = len(joints)
    factors = actuator_read_factors(mech, [table.unit(k) for k in joints], name)
    q_act = data[:, :n] / factors
    check_actuator_ranges(mech, q_act, name, [cols[k] for k in joints])
    out = []
    for k in range(len(setup.marker_sets)):
        positions = data[:, n + 3 * k : n + 3 * k + 3] / lf
        frame = mech.measured_frame if k == 0 else marker_frame(k)[1]
        out.append(
            Measurements(q_act, positions, None, ("x", "y", "z"), frame, tuple(mech.actuated))
        )
    return tuple(out)
