"""Marker tables: motion-capture or tracker exports with joint readings, read as they are.

A foreign delimited table (see :mod:`pincal.io._delimited`: ``,`` ``;`` or tab, one
title line — the first line holding the marker columns' titles, an export's preamble
lines before it skipped and said) with one row per pose: a column per actuated joint
and, among any number of other columns (further markers, frame numbers, time stamps),
the three position columns of the marker(s) used, named by the
:class:`pincal.measure.MarkerSetup` (e.g. ``x1, y1, z1``; further markers in its
``more_columns``) in its ``length_unit``, or in the unit of the column's title (``x1
[mm]``: the title wins, said in a note). The positions are in the instrument's frame;
the rows become position-only :class:`pincal.measure.Measurements` of the marker frame
``tool`` (further markers: ``marker2``, ``marker3``, …, one set each).

A 6-D marker body adds orientation columns in a declared convention (the setup's
``orientation_columns`` and ``orientation``: roll-pitch-yaw, xyz-Euler, rotation
vector in degrees or radians, or a quaternion; read by
:mod:`pincal.io._marker_orientation`): its rows become pose measurements (``x y z rx
ry rz``) of the frame ``tool``.

Joint columns are read as in measurement files (:mod:`pincal.io._joint_columns`): named
as the URDF joint (any case) or mapped by ``columns`` in the model's sidecar; units from
the title's bracket (``[deg]``), else ``joint_units``, else SI; readings relative to a
reference pose with ``joint_reference`` (``home`` or values). ``#`` lines before the
title line may give the same declarations (``# joint_units: deg``), and win.

A marker the camera did not see leaves its cells empty (or ``nan``): such a row is left
out, named in the notes of :func:`read_marker_data` (the joints still have to be
numbers: a missing joint reading is an error).

The bounds of :mod:`pincal.io._marker_checks` hold: a column used has a title no other
column has, coordinates within 10 km, positions of the nominal link's size (a unit
ratio away: the unit is named).

Exports often repeat one marker under two names (the same values in two column
triples); :func:`distinct_markers` finds such copies among the markers chosen and keeps
one, saying so — a copy fitted as a second marker would count every point twice.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from pincal._files import read_text
from pincal.errors import ColumnError, MeasurementFileError, MeasurementFormatError
from pincal.io._csv import Header, parse_column
from pincal.io._delimited import Table, read_table
from pincal.io._joint_columns import HEADER_KEYS, joint_columns, read_joints
from pincal.io._marker_checks import (
    check_coordinates,
    check_scale,
    check_unique_titles,
    position_triples,
)
from pincal.io._marker_orientation import orientation_values, read_rotations
from pincal.io._names import is_decimal
from pincal.io._units import LENGTH_UNITS, unit_factor
from pincal.measure import MarkerSetup, Measurements, marker_frame
from pincal.model import COMPONENTS, JointReadings, Mechanism

__all__ = [
    "MarkerData",
    "distinct_markers",
    "read_marker_data",
    "read_marker_sets",
    "read_marker_table",
]

XYZ = ("x", "y", "z")
_MISSING = ("", "nan", "-nan", "na", "n/a", "null", "none")


@dataclass(frozen=True)
class MarkerData:
    """A marker table read: one measurement set per marker, and what was left out.

    Attributes:
        sets: per marker of the setup, position-only measurements (same rows); a
            marker body with orientation columns: pose measurements.
        dropped: 1-based file lines of rows left out (a marker cell missing).
        notes: what the reader did, in words (rows left out, declarations applied).
    """

    sets: tuple[Measurements, ...]
    dropped: tuple[int, ...] = ()
    notes: tuple[str, ...] = ()


def read_marker_table(path: str | Path, mech: Mechanism, setup: MarkerSetup) -> Measurements:
    """The first marker's rows of :func:`read_marker_sets` (see there)."""
    return read_marker_sets(path, mech, setup)[0]


def read_marker_sets(
    path: str | Path, mech: Mechanism, setup: MarkerSetup
) -> tuple[Measurements, ...]:
    """The measurement sets of :func:`read_marker_data` (see there)."""
    return read_marker_data(path, mech, setup).sets


def _comment_header(path: str | Path) -> Header:
    """``# key: value`` lines before the title line, for the joint declarations only."""
    header: Header = {}
    for line in read_text(path, "delimited table", error=MeasurementFileError).splitlines():
        s = line.strip()
        if not s:
            continue
        if not s.startswith("#"):
            break
        key, sep, value = s[1:].partition(":")
        if sep and key.strip() in HEADER_KEYS:
            header.setdefault(key.strip(), []).append(value.strip())
    return header


def _cell(table: Table, i: int, k: int) -> float:
    """A marker cell as a number, NaN when the marker was not seen (empty, ``nan``)."""
    text = table.rows[i][k].strip()
    if text.lower() in _MISSING:
        return math.nan
    if table.decimal == ",":
        text = text.replace(",", ".")
    if not is_decimal(text):
        return table.number(i, k)  # raises, naming the line and column
    return float(text)


def _columns_hint(table: Table) -> str:
    """How to name the marker's columns, with the file's x/y/z-like triples."""
    found = [",".join(t) for t in position_triples(table.columns)]
    if not found:
        return ("name the marker's three position columns with --marker-columns X,Y,Z "
                "(markers.columns in a campaign)")  # fmt: skip
    # a unit in parentheses is part of the title, not read: say it with --length-unit
    unit = found[0].split(",")[0].rpartition("(")[2].rstrip(") ").strip().lower()
    unit_opt = f" --length-unit {unit}" if unit in LENGTH_UNITS and "(" in found[0] else ""
    hint = (f"name the marker's position columns with --marker-columns {found[0]}{unit_opt} "
            "(markers.columns in a campaign)")  # fmt: skip
    if len(found) > 1:
        hint += f"; x/y/z-like triples in the file: {' '.join(found[:8])}"
        hint += " …" if len(found) > 8 else ""
    return hint


def _marker_columns(table: Table, setup: MarkerSetup) -> list[int]:
    out = []
    for c in (c for triple in setup.marker_sets for c in triple):
        k = table.find(c, [c], {})
        if k is None:
            like = [t for t in table.columns if t.split("(")[0].strip().lower() == c.lower()]
            hint = (f" ({like[0]!r} is one with its unit in parentheses: write the unit in "
                    f"brackets, '{c} [mm]', or name it with --marker-columns)") if like else ""
            raise ColumnError(
                f"{table.name}: no marker column {c!r}{hint}; {_columns_hint(table)}; columns "
                f"are {list(table.columns)}",
                missing=[c],
            )
        out.append(k)
    return out


def _marker_values(table: Table, setup: MarkerSetup) -> np.ndarray:
    """(rows, 3 × markers) marker cells as written, NaN where the marker was not seen."""
    idx = _marker_columns(table, setup)
    return np.array([[_cell(table, i, k) for k in idx] for i in range(len(table.rows))])


def _length_factors(table: Table, setup: MarkerSetup) -> tuple[np.ndarray, list[str]]:
    """Units per metre of each marker column (the title's unit, else the setup's), notes."""
    declared = unit_factor(LENGTH_UNITS, setup.length_unit, "length", table.name)
    factors, other = [], []
    for k in _marker_columns(table, setup):
        unit = table.unit(k)
        if unit is None:
            factors.append(declared)
            continue
        factors.append(unit_factor(LENGTH_UNITS, unit, "length",
                                   f"{table.name} column {table.columns[k]!r}"))  # fmt: skip
        if unit != setup.length_unit:
            other.append(repr(table.columns[k]))
    notes = [f"{table.name}: column(s) {', '.join(other)} read in their title's unit, not "
             f"{setup.length_unit} (the declared length unit)"] if other else []  # fmt: skip
    return np.array(factors), notes


def _table(path: str | Path, setup: MarkerSetup) -> Table:
    """The table, its title line the first line holding the marker columns' titles."""
    table = read_table(path, titles=[c for triple in setup.marker_sets for c in triple])
    check_titles(table)
    return table


def distinct_markers(path: str | Path, setup: MarkerSetup) -> tuple[MarkerSetup, tuple[str, ...]]:
    """``setup`` without markers whose columns repeat an earlier marker's, value for value.

    Missing cells (a marker not seen) compare equal to missing cells.

    Returns:
        (the setup with its copies left out, a sentence per copy left out).

    Raises:
        ColumnError, MeasurementFormatError, BadValueError: as :func:`read_marker_sets`.
    """
    if not setup.more_columns:
        return setup, ()
    table = _table(path, setup)
    data = _marker_values(table, setup)
    values = [data[:, 3 * k : 3 * k + 3] for k in range(len(setup.marker_sets))]
    keep: list[int] = []
    notes = []
    for k, v in enumerate(values):
        same = next((j for j in keep if np.array_equal(values[j], v, equal_nan=True)), None)
        if same is None:
            keep.append(k)
            continue
        a, b = setup.marker_sets[k], setup.marker_sets[same]
        notes.append(
            f"{table.name}: columns {','.join(a)} repeat {','.join(b)} value for value (one "
            f"marker exported twice): used once, as {','.join(b)}"
        )
    sets = [setup.marker_sets[k] for k in keep]
    links = tuple(setup.marker_links[k] for k in keep[1:]) if setup.more_links else ()
    kept = replace(setup, columns=sets[0], more_columns=tuple(sets[1:]), more_links=links)
    return kept, tuple(notes)


def check_titles(table: Table) -> None:
    """A first line of numbers is data, not titles: say so before any column is missed."""
    if table.columns and all(is_decimal(c.replace(",", ".")) for c in table.columns):
        raise MeasurementFormatError(
            f"{table.name}: the first line holds numbers, not column titles; add a title line "
            "naming every column (joints as the URDF joints or mapped by 'columns' in the "
            "sidecar, the marker columns as given to --marker-columns / markers.columns)"
        )


def joint_titles(table: Table, mech: Mechanism) -> list[tuple[str, str | None]]:
    """(name, bracketed unit) of each title; a joint's name in another case is the joint's."""
    joints = {j.lower(): j for j in mech.actuated}
    out = []
    for title in table.columns:
        try:
            name, unit = parse_column(title)
        except MeasurementFormatError:
            name, unit = title, None
        out.append((joints.get(name.lower(), name), unit))
    return out


def read_marker_data(path: str | Path, mech: Mechanism, setup: MarkerSetup) -> MarkerData:
    """Marker positions [m] (and a body's orientations) and joint values [m, rad] of every row.

    Args:
        path: the table (never modified).
        mech: the chain of :func:`pincal.measure.marker_mechanism` (its actuated joints
            name the joint columns; its sidecar maps, scales and references them).
        setup: the marker columns and their unit.

    Returns:
        Per marker of ``setup.marker_sets``, position-only measurements (same rows) of
        its frame (:func:`pincal.measure.marker_frame`: ``mech.measured_frame`` for the
        first), no declared noise; rows where a marker used was not seen left out.
        With orientation columns, the body's rotations (instrument frame) too and the
        components ``x y z rx ry rz``.

    Raises:
        ColumnError: a joint, marker or orientation column is missing (the columns
            found are listed).
        MeasurementFormatError: no data rows, no complete row, an unknown unit, a
            malformed declaration.
        BadValueError: a cell that is not a number, a joint cell empty (names the line
            and column), a joint reading implausible for its unit.
        ActuatorRangeError: a joint reading outside its URDF range.
        NonFiniteValueError: an infinite orientation cell.
        OrientationValueError: an orientation value not of the declared convention (a
            quaternion not of unit norm, an angle beyond a turn).
    """
    table = _table(path, setup)
    name = table.name
    if not table.rows:
        raise MeasurementFormatError(f"{name}: no data rows")
    factors, unit_notes = _length_factors(table, setup)
    parsed = joint_titles(table, mech)
    named = [k for k, (n, _) in enumerate(parsed) if n in mech.actuated]
    check_unique_titles(table, [*_marker_columns(table, setup), *named])  # before "missing"
    joints, decl = joint_columns(mech, _comment_header(path), parsed, name)
    read_columns = [*_marker_columns(table, setup), *joints]
    if setup.measures_orientation:
        found = (table.find(c, [c], {}) for c in setup.orientation_columns)
        read_columns += [k for k in found if k is not None]
    check_unique_titles(table, read_columns)
    markers = _marker_values(table, setup)
    check_coordinates(table, markers, _marker_columns(table, setup), factors)
    seen = ~np.isnan(markers).any(axis=1)
    angles = orientation_values(table, setup, _cell) if setup.measures_orientation else None
    if angles is not None:
        seen &= ~np.isnan(angles).any(axis=1)
    if not seen.any():
        used = ", ".join(" ".join(c) for c in setup.marker_sets)
        raise MeasurementFormatError(
            f"{name}: no row has every marker used ({used}): a marker never seen; choose "
            "the markers present with the marker columns"
        )
    rows = np.flatnonzero(seen)
    raw = np.array([[table.number(int(i), k) for k in joints] for i in rows])
    titles = [table.columns[k] for k in joints]
    units = [parsed[k][1] for k in joints]
    q_act = read_joints(mech, raw, decl, units, titles, name)
    dropped = tuple(table.lines[i] for i in np.flatnonzero(~seen))
    notes = [*_preamble_note(table), *unit_notes, *_home_note(mech, decl)]
    notes += _off_chain_note(table, parsed, mech)
    if dropped:
        shown_lines = ", ".join(map(str, dropped[:10])) + (" …" if len(dropped) > 10 else "")
        notes.append(
            f"{name}: {len(dropped)} of {len(table.rows)} rows left out, a marker used not "
            f"seen (empty or nan cells): lines {shown_lines}"
        )
    rotations = None
    if angles is not None:
        rotations, said = read_rotations(table, setup, angles, rows)
        notes += said
    positions = markers[rows] / factors
    check_scale(mech, q_act, positions[:, :3], _unit_read(table, setup), name,
                [table.lines[int(i)] for i in rows])  # fmt: skip
    out = []
    for k in range(len(setup.marker_sets)):
        frame = mech.measured_frame if k == 0 else marker_frame(k)[1]
        R, comps = (rotations, COMPONENTS) if k == 0 and rotations is not None else (None, XYZ)
        out.append(Measurements(q_act, positions[:, 3 * k : 3 * k + 3], R, comps, frame,
                                tuple(mech.actuated)))  # fmt: skip
    return MarkerData(tuple(out), dropped, tuple(notes))


def _unit_read(table: Table, setup: MarkerSetup) -> str:
    """The unit the first marker's x column was read in."""
    return table.unit(_marker_columns(table, setup)[0]) or setup.length_unit


def _preamble_note(table: Table) -> list[str]:
    if not table.preamble:
        return []
    first, last = table.preamble[0], table.preamble[-1]
    shown_lines = f"{first}–{last}" if last != first else str(first)
    return [f"{table.name}: line(s) {shown_lines} before the title line skipped (an export's "
            "preamble: the title line is the first holding the marker columns)"]  # fmt: skip


def _home_note(mech: Mechanism, decl: JointReadings) -> list[str]:
    """What ``joint_reference: home`` meant, in values (one home everywhere)."""
    if decl.reference != "home":
        return []
    home = mech.actuators_of(mech.q_home)
    values = ", ".join(f"{j} = {v:.6g}" for j, v in zip(mech.actuated, home, strict=True))
    return [f"joint readings relative to home (joint_reference: home), the model's home as "
            f"`pincal info MODEL --frame LINK` prints it [rad or m]: {values}"]  # fmt: skip


def _off_chain_note(
    table: Table, parsed: list[tuple[str, str | None]], mech: Mechanism
) -> list[str]:
    """The joint columns of joints the model holds fixed (off the measured chain), once."""
    fixed = {n for n, j in mech.tree.joints.items() if not j.movable}
    names = [n for n, _ in parsed if n in fixed and n not in mech.actuated]
    if not names:
        return []
    shown = ", ".join(names[:8]) + (f" … ({len(names)} in all)" if len(names) > 8 else "")
    return [f"{table.name}: columns {shown} are joints off the calibrated chain (held fixed "
            "in the model): not used; a marker on a link they move calibrates them (--link "
            "LINK, or several: --link L1,L2)"]  # fmt: skip
