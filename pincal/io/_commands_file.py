"""Command files: actuator values to send to the machine, one row per target pose.

::

    # pincal commands 1
    pose,leg1_slide [mm],…,leg6_slide [mm]

Column ``pose`` (index of the target) then one column per actuated joint; a
bracketed unit is optional (SI without one). :func:`read_actuator_rows` is a lenient
reader of any CSV naming the actuated joints (for viewing).
"""

from __future__ import annotations

import csv
import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from pincal._files import read_text
from pincal._yaml import shown
from pincal.errors import (
    ColumnError,
    MeasurementError,
    MeasurementFileError,
    MeasurementFormatError,
    clip,
)
from pincal.io._csv import (
    actuator_columns,
    fmt,
    parse_column,
    parse_numbers,
    split_file,
    write_csv,
)
from pincal.io._names import is_decimal, is_non_finite
from pincal.io._units import (
    actuator_read_factors,
    actuator_write_factors,
    check_actuator_ranges,
)
from pincal.model import Mechanism

__all__ = ["MAX_POSES_BYTES", "read_actuator_rows", "read_commands", "write_commands"]

#: largest file :func:`read_actuator_rows` reads [bytes]
MAX_POSES_BYTES = 5_000_000


def write_commands(
    path: str | Path,
    actuated: Sequence[str],
    q_act: np.ndarray,
    indices: Sequence[int] | None = None,
    actuator_units: Sequence[str] | None = None,
) -> Path:
    """Write actuator commands atomically, with the target index per row.

    Args:
        path: output file.
        actuated: actuated joint names (n_act,).
        q_act: commands (m, n_act) [m, rad] (a single row (n_act,) is accepted).
        indices: target index per row (m,); default 0 … m − 1.
        actuator_units: optional unit per actuator column (``"mm"``, ``"deg"``…); SI if None.

    Returns:
        The written path.

    Raises:
        MeasurementError: bad ``actuator_units``.
    """
    q_act = np.atleast_2d(np.asarray(q_act, dtype=float))
    idx = list(range(q_act.shape[0])) if indices is None else list(indices)
    columns = ["pose", *actuator_columns(actuated, actuator_units)]
    fac = actuator_write_factors(actuator_units, len(actuated))
    rows = [[str(int(k)), *(fmt(v) for v in row * fac)] for k, row in zip(idx, q_act, strict=True)]
    return write_csv(path, "commands", [], columns, rows)


def read_commands(path: str | Path, mech: Mechanism) -> tuple[np.ndarray, np.ndarray]:
    """Target indices and commands from a command file.

    Args:
        path: the command file.
        mech: the model naming the actuated joints.

    Returns:
        (indices (m,) int, q_act (m, n_act) [m, rad]).

    Raises:
        MeasurementFormatError: not a command file, or unknown unit.
        ColumnError: missing ``pose`` or actuator columns.
        BadValueError, NonFiniteValueError: a cell that is not a finite number.
        ActuatorRangeError: a command far outside its joint's URDF limits.
        MeasurementFileError, InputLimitError: unreadable, not a regular file, too large.
    """
    name = Path(path).name
    _, columns, rows = split_file(path, "commands")
    parsed = [parse_column(c) for c in columns]
    names = [p[0] for p in parsed]
    missing = [c for c in ("pose", *mech.actuated) if c not in names]
    if missing:
        raise ColumnError(f"{name}: missing columns {missing}", missing=missing)
    data = parse_numbers(rows, columns, name)
    act = [names.index(j) for j in mech.actuated]
    fac = actuator_read_factors(mech, [parsed[k][1] for k in act], name)
    q_act = data[:, act] / fac
    check_actuator_ranges(mech, q_act, name, [columns[k] for k in act])
    return data[:, names.index("pose")].astype(int), q_act


def read_actuator_rows(
    path: str | Path, actuated: tuple[str, ...], max_rows: int | None = None
) -> np.ndarray:
    """Actuator rows (m, n_act) [m, rad] from any CSV whose header names the joints.

    Lenient on purpose (for viewing): ``#`` lines are comments, other columns are
    ignored, values are SI. A command file (:func:`write_commands`) qualifies.

    Args:
        path: the CSV file (at most :data:`MAX_POSES_BYTES` bytes, UTF-8).
        actuated: actuated joint names (n_act,) the header must contain.
        max_rows: refuse files with more rows than this (None: no limit).

    Raises:
        MeasurementError: unreadable file, missing columns, non-numeric or
            non-finite values, no rows.
    """
    path = Path(path)
    text = read_text(path, "poses file", MAX_POSES_BYTES, MeasurementFileError)
    lines = [
        (n, line)
        for n, line in enumerate(text.splitlines(), 1)
        if not line.lstrip().startswith("#")
    ]
    lines = [(n, line) for n, line in lines if line.strip()]
    if not lines:
        raise MeasurementError(f"poses file {str(path)!r} is empty; expected a header line")
    try:
        header = [h.strip() for h in next(csv.reader([lines[0][1]]))]
    except csv.Error as exc:
        raise MeasurementFormatError(
            f"{path.name} line {lines[0][0]}: cannot be split into cells ({clip(str(exc))})"
        ) from None
    missing = [name for name in actuated if name not in header]
    if missing:
        raise MeasurementError(
            f"poses file {str(path)!r}: header lacks actuated joint(s) {missing}; the header "
            f"must name the actuated joints {list(actuated)}"
        )
    columns = [header.index(name) for name in actuated]
    rows = []
    for n, line in lines[1:]:
        try:
            cells = next(csv.reader([line]), [])
        except csv.Error as exc:
            raise MeasurementFormatError(
                f"{path.name} line {n}: cannot be split into cells ({clip(str(exc))})"
            ) from None
        if len(cells) != len(header):
            raise MeasurementError(
                f"{path.name} line {n}: {len(cells)} values for {len(header)} header columns"
            )
        bad = [cells[c] for c in columns if not is_decimal(cells[c])]
        if bad and not is_non_finite(bad[0]):
            raise MeasurementError(
                f"{path.name} line {n}: non-numeric value {shown(bad[0])}; write plain decimal "
                "numbers (e.g. 12.5 or -1e-3)"
            )
        row = [float(cells[c]) for c in columns]
        if not all(math.isfinite(v) for v in row):
            raise MeasurementError(f"{path.name} line {n}: NaN or infinite value")
        rows.append(row)
    if not rows:
        raise MeasurementError(f"poses file {str(path)!r} has a header but no poses")
    if max_rows is not None and len(rows) > max_rows:
        raise MeasurementError(
            f"poses file {str(path)!r} has {len(rows)} poses; at most {max_rows}"
        )
    return np.array(rows, dtype=float)
