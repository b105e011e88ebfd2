"""The marker route's bounds: column titles used once, positions of a plausible size.

The checks a marker table passes after it is read and before any fit, as a pose file
does (:mod:`pincal.io._measurement_file`):

- a column the calibration uses (marker, orientation or joint column) has a title no
  other column has: with two ``x`` columns, which one is the marker is a guess;
- every marker coordinate is within :data:`pincal.io._measurement_header.MAX_COORDINATE`
  of the instrument's origin (a ``1e300`` cell overflows the closed-form registration);
- the positions spread about as much as the nominal marker link over the same joint
  readings: a spread a unit ratio away (millimetres read as metres) names the unit.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from pincal.errors import BadValueError, ColumnError, UnitMismatchError
from pincal.io._delimited import Table
from pincal.io._measurement_header import MAX_COORDINATE
from pincal.io._units import LENGTH_UNITS
from pincal.model import Mechanism

__all__ = [
    "check_coordinates",
    "check_scale",
    "check_unique_titles",
    "position_triples",
    "title_key",
]

#: positions spread more than this factor away from the nominal link's: a unit is wrong
SCALE_FACTOR = 20.0
#: a unit ratio explains a spread ratio within this factor
UNIT_MATCH = 3.0
#: the nominal link must move at least this much [m] for the comparison to mean anything
MIN_SPREAD = 0.02
#: a row is wild beyond SCALE_FACTOR times the nominal reach, and never within
#: SCALE_FACTOR times this [m] (an unknown marker offset adds up to a link's size)
WILD_FLOOR = 1.0
#: rows compared at most (evenly spaced): the spread of a table needs no more
SCALE_ROWS = 500


def title_key(title: str) -> str:
    """A title as columns are matched: any case, without a bracketed unit."""
    from pincal.io._csv import parse_column
    from pincal.io._delimited import parsable_title

    return (parse_column(title)[0] if parsable_title(title) else title).strip().lower()


def _bare(title: str) -> str:
    """A title without its bracketed unit, as written (``x1 [mm]`` → ``x1``)."""
    from pincal.io._csv import parse_column
    from pincal.io._delimited import parsable_title

    return (parse_column(title)[0] if parsable_title(title) else title).strip()


def position_triples(columns: Sequence[str]) -> list[tuple[str, str, str]]:
    """The column triples of ``columns`` that look like a marker's x, y, z.

    Titles (any case, without a bracketed unit) that differ only in one letter x / y / z
    at the same place (``x1 y1 z1``, ``hand_X hand_Y hand_Z``), in the order of their x
    column; each as the titles are written without the unit, for a ``--marker-columns``
    suggestion.
    """
    bare = [_bare(c) for c in columns]
    index = {b.lower(): b for b in reversed(bare)}  # first title of each key
    out: list[tuple[str, str, str]] = []
    for name in bare:
        low = name.lower()
        for i, ch in enumerate(low):
            if ch != "x":
                continue
            y, z = (low[:i] + c + low[i + 1 :] for c in "yz")
            triple = (name, index.get(y, ""), index.get(z, ""))
            if all(triple) and triple not in out:
                out.append(triple)
    return out


def check_unique_titles(table: Table, used: Sequence[int]) -> None:
    """Refuse a used column whose title another column has too.

    Raises:
        ColumnError: naming the title and both columns (1-based positions).
    """
    keys = [title_key(c) for c in table.columns]
    for k in used:
        others = [j for j, key in enumerate(keys) if key == keys[k] and j != k]
        if others:
            a, b = sorted((k, others[0]))
            raise ColumnError(
                f"{table.name}: columns {a + 1} ({table.columns[a]!r}) and {b + 1} "
                f"({table.columns[b]!r}) have the same title, and the calibration reads one "
                "of them: which one is meant is a guess; rename one (e.g. add the marker's "
                "name) and give that title to the marker or joint columns",
                unknown=[table.columns[b]],
            )


def check_coordinates(table: Table, values: np.ndarray, columns: Sequence[int],
                      factors: np.ndarray) -> None:  # fmt: skip
    """Refuse a marker coordinate farther than MAX_COORDINATE from the instrument's origin.

    Args:
        table: the table (names, lines).
        values: (rows, c) marker cells as written (NaN: not seen).
        columns: the table column of each of the c values.
        factors: (c,) units per metre of each value.

    Raises:
        BadValueError: naming the line, the column and the value.
    """
    far = np.argwhere(np.abs(values) > MAX_COORDINATE * factors)
    if far.size:
        i, j = (int(v) for v in far[0])
        title = table.columns[columns[j]]
        raise BadValueError(
            f"{table.name} line {table.lines[i]}, column {title!r}: {values[i, j]:g} is more "
            f"than {MAX_COORDINATE / 1e3:g} km from the instrument's origin; check the value "
            "and the length unit",
            i + 1,
            title,
        )


def _spread(points: np.ndarray) -> float:
    """Median distance of points (n, 3) from their coordinate-wise median.

    Robust: a few wild rows (one cell typed 9e6 mm) do not read as a unit ratio.
    """
    return float(np.median(np.linalg.norm(points - np.median(points, axis=0), axis=1)))


def _check_wild_rows(nominal: np.ndarray, positions: np.ndarray, name: str,
                     lines: Sequence[int]) -> None:  # fmt: skip
    """Refuse a row (n, 3) [m] far beyond the nominal link's reach about the median point."""
    reach = max(float(np.linalg.norm(nominal - np.median(nominal, axis=0), axis=1).max()),
                WILD_FLOOR)  # fmt: skip
    d = np.linalg.norm(positions - np.median(positions, axis=0), axis=1)
    far = np.flatnonzero(d > SCALE_FACTOR * reach)
    if not far.size:
        return
    i = int(far[np.argmax(d[far])])
    raise BadValueError(
        f"{name} line {lines[i]}: the marker lies {d[i]:.3g} m from the table's median marker "
        f"position, beyond {SCALE_FACTOR * reach:.3g} m ({SCALE_FACTOR:g}× the nominal link's "
        f"reach, at least {SCALE_FACTOR * WILD_FLOOR:g} m; {len(far)} such row(s)): a "
        "mistyped cell? correct or delete the row",
        i + 1,
        "marker",
    )


def check_scale(mech: Mechanism, q_act: np.ndarray, positions: np.ndarray, unit: str,
                name: str, lines: Sequence[int]) -> None:  # fmt: skip
    """Refuse positions whose spread is a length-unit ratio away from the nominal link's.

    The marker's spread about its median point is compared with that of the nominal
    measured frame over the same joint readings (rotation and translation of the
    instrument do not change a spread; an unknown marker offset changes it by far less
    than :data:`SCALE_FACTOR`).

    Args:
        mech: the marker chain (nominal).
        q_act: (n, n_act) joint readings [m, rad].
        positions: (n, 3) the first marker's positions [m], as read.
        unit: the unit the positions were read in (for the message).
        name: file name.
        lines: (n,) the file line of each row (for the message).

    Raises:
        BadValueError: the spreads agree but a row lies more than :data:`SCALE_FACTOR`
            times the nominal link's largest distance from the median point (at least
            :data:`WILD_FLOOR`; one wild cell: the line is named).
        UnitMismatchError: the ratio is beyond :data:`SCALE_FACTOR` and a ratio of two
            length units explains it within :data:`UNIT_MATCH` (the message names the
            unit to declare).
    """
    rows = np.unique(np.linspace(0, len(q_act) - 1, min(len(q_act), SCALE_ROWS)).astype(int))
    if len(rows) < 3:
        return
    nominal = np.array([mech.frame_placement(q).translation
                        for q in mech.configurations(q_act[rows])])  # fmt: skip
    s_nom, s_meas = _spread(nominal), _spread(positions[rows])
    if s_nom < MIN_SPREAD or s_meas == 0 or not math.isfinite(s_meas):
        return
    ratio = s_meas / s_nom
    if 1 / SCALE_FACTOR <= ratio <= SCALE_FACTOR:
        _check_wild_rows(nominal, positions, name, lines)
        return
    per_m = LENGTH_UNITS[unit] if unit in LENGTH_UNITS else 1.0
    for other, f in LENGTH_UNITS.items():
        if other == unit:
            continue
        expected = f / per_m  # the values are in `other`, read as `unit`
        if abs(math.log(ratio / expected)) <= math.log(UNIT_MATCH):
            raise UnitMismatchError(
                f"{name}: the marker positions spread {ratio:.3g}× as far as the nominal "
                f"marker link over the same joint readings ({s_meas:.3g} m against "
                f"{s_nom:.3g} m, median distance from their median): the marker columns look "
                f"like {other} read as {unit}; declare --length-unit {other} "
                f"(markers.length_unit in a campaign, or title the columns 'x [{other}]')"
            )
