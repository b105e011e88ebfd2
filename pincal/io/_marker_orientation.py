"""The orientation columns of a marker table (a 6-D marker body), read and checked.

The columns and their convention are declared by the :class:`pincal.measure.MarkerSetup`
(``orientation_columns``, ``orientation``: see :mod:`pincal.measure._orientation`). A
body the camera did not see leaves its cells empty (or ``nan``): such a row is left out
as for a missing marker. Any other cell must be a finite number of the declared
convention: a quaternion of unit norm (within
:data:`pincal.measure.QUATERNION_TOLERANCE`), angles within one turn (360° or 2π rad).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from pincal.errors import ColumnError, NonFiniteValueError, OrientationValueError
from pincal.io._delimited import Table
from pincal.measure import MarkerSetup, orientation_problems, rotation_matrices

__all__ = ["orientation_values", "read_rotations"]


def orientation_values(
    table: Table, setup: MarkerSetup, cell: Callable[[Table, int, int], float]
) -> np.ndarray:
    """(rows, k) orientation cells in the declared unit, NaN where the body was not seen.

    Args:
        table: the marker table.
        setup: its set-up (with orientation columns).
        cell: (table, row, column) → float, NaN for an empty cell (the marker reader's).

    Raises:
        ColumnError: an orientation column is missing (the columns found are listed).
        NonFiniteValueError: an infinite cell (names the line and column).
    """
    idx = []
    for c in setup.orientation_columns:
        k = table.find(c, [c], {})
        if k is None:
            raise ColumnError(
                f"{table.name}: no orientation column {c!r} (--orientation-columns / "
                f"markers.orientation_columns); columns are {list(table.columns)}",
                missing=[c],
            )
        idx.append(k)
    values = np.array([[cell(table, i, k) for k in idx] for i in range(len(table.rows))])
    values = values.reshape(len(table.rows), len(idx))
    for i, j in zip(*np.nonzero(np.isinf(values)), strict=True):
        raise NonFiniteValueError(
            f"{table.name} line {table.lines[i]}, column {table.columns[idx[j]]!r}: "
            f"{values[i, j]} is not a finite orientation value",
            int(i) + 1,
            table.columns[idx[j]],
        )
    return values


def read_rotations(
    table: Table, setup: MarkerSetup, values: np.ndarray, rows: np.ndarray
) -> tuple[np.ndarray, tuple[str, ...]]:
    """(len(rows), 3, 3) rotations of the rows kept, and notes on the values.

    Args:
        table: the marker table.
        setup: its set-up (``orientation`` names the convention).
        values: (table rows, k) from :func:`orientation_values`.
        rows: 0-based table rows kept (every cell seen).

    Raises:
        OrientationValueError: a value that cannot be of the convention (names the line,
            the column and what is wrong, and what to declare instead).
    """
    convention = str(setup.orientation)
    kept = values[rows]
    problems = orientation_problems(kept, convention)
    if problems:
        r, k, why = problems[0]
        line = table.lines[int(rows[r])]
        column = ",".join(setup.orientation_columns) if k < 0 else setup.orientation_columns[k]
        hint = (
            "normalise the quaternions, or check the columns' order (w x y z or x y z w)"
            if convention.startswith("quat")
            else "check the convention and the unit declared (--orientation, e.g. rpy-deg)"
        )
        raise OrientationValueError(
            f"{table.name} line {line}, column {column}: {why} — not {convention} "
            f"({len(problems)} row(s) so); {hint}",
            int(rows[r]) + 1,
            column,
        )
    notes: tuple[str, ...] = ()
    if convention.endswith("-deg") and kept.size:
        peak, spread = float(np.abs(kept).max()), float(np.ptp(kept, axis=0).max())
        if peak <= np.pi and spread > 0.1:
            notes = (
                f"{table.name}: every orientation value lies within ±π (largest "
                f"{peak:.3g}) although {convention} declares degrees: if they are "
                f"radians, declare {convention.replace('-deg', '-rad')}",
            )
    return rotation_matrices(kept, convention), notes
