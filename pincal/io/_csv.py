"""The CSV core shared by every pincal file kind.

A pincal file is UTF-8 text: a magic line ``# pincal <kind> 1``, header lines
``# key: value`` (repeatable keys are collected in order; a ``#`` after the value
starts a comment), one column line (a bracketed unit is optional: ``leg1 [mm]``),
then the data rows. Blank lines and ``#`` lines between rows are ignored. Values are
written with ``repr`` (the shortest form that reads back to the same float) and
files are replaced atomically (temporary file + rename).
"""

from __future__ import annotations

import csv
import io
import math
import re
from collections.abc import Iterable, Sequence
from pathlib import Path

import numpy as np

from pincal.errors import (
    BadValueError,
    MeasurementError,
    MeasurementFormatError,
    NonFiniteValueError,
)
from pincal.io._atomic import atomic_write_text

__all__ = [
    "Header",
    "actuator_columns",
    "fmt",
    "header_value",
    "parse_column",
    "parse_numbers",
    "positive_value",
    "split_file",
    "write_csv",
]

#: header key → its values in file order (a key may repeat, e.g. ``target``)
Header = dict[str, list[str]]

_COLUMN = re.compile(r"^\s*([^\[\]]+?)\s*(?:\[\s*([A-Za-z]+)\s*\])?\s*$")


def fmt(x: float) -> str:
    """``x`` as the shortest text that reads back to the same float."""
    return repr(float(x))


def _read_lines(path: str | Path) -> list[str]:
    try:
        return Path(path).read_text(encoding="utf-8").splitlines()
    except OSError as exc:
        raise MeasurementError(f"cannot read {str(path)!r}: {exc.strerror}") from exc
    except UnicodeDecodeError as exc:
        raise MeasurementFormatError(f"{str(path)!r} is not a UTF-8 text file") from exc


def split_file(path: str | Path, magic: str) -> tuple[Header, list[str], list[list[str]]]:
    """Header (key → values, repeated keys collected), column names, data rows (text).

    Args:
        path: the file.
        magic: the expected kind of the first line ``# pincal <magic> 1``.

    Raises:
        MeasurementError: the file cannot be read.
        MeasurementFormatError: not UTF-8, another pincal kind, no magic line, no
            column line.
    """
    lines = _read_lines(path)
    name = Path(path).name
    header: Header = {}
    body: list[str] = []
    seen_magic = False
    for n, line in enumerate(lines, start=1):
        s = line.strip()
        if not s:
            continue
        if s.startswith("#"):
            if body:
                continue  # comments between rows are allowed
            text = s[1:].strip()
            if text.startswith("pincal "):
                if text.split()[1:2] != [magic]:
                    raise MeasurementFormatError(
                        f"{name} line {n}: this is a {text!r} file, expected 'pincal {magic}'"
                    )
                seen_magic = True
                continue
            if ":" in text:
                key, _, value = text.partition(":")
                header.setdefault(key.strip().lower(), []).append(value.split("#")[0].strip())
            continue
        body.append(line)
    if not seen_magic:
        raise MeasurementFormatError(f"{name}: missing the first header line '# pincal {magic} 1'")
    if not body:
        raise MeasurementFormatError(f"{name}: no column line and no data rows")
    rows = list(csv.reader(body, skipinitialspace=True))
    columns = [c.strip() for c in rows[0]]
    return header, columns, rows[1:]


def header_value(header: Header, key: str, default: str | None, name: str) -> str:
    """The single value of header ``key``, or ``default`` when absent.

    Raises:
        MeasurementFormatError: ``key`` is absent and required (``default`` None), or
            given more than once.
    """
    if key not in header:
        if default is None:
            raise MeasurementFormatError(f"{name}: header line '# {key}: …' is required")
        return default
    if len(header[key]) > 1:
        raise MeasurementFormatError(f"{name}: header '{key}' given {len(header[key])} times")
    return header[key][0]


def positive_value(text: str, key: str, name: str) -> float:
    """Header value ``text`` of ``key`` as a finite number > 0.

    Raises:
        MeasurementFormatError: not a number, not finite or not positive.
    """
    try:
        v = float(text)
    except ValueError:
        raise MeasurementFormatError(f"{name}: header {key!r} must be a number") from None
    if not (math.isfinite(v) and v > 0):
        raise MeasurementFormatError(f"{name}: header {key!r} must be finite and > 0")
    return v


def parse_column(col: str) -> tuple[str, str | None]:
    """(name, unit or None) of a column title such as ``leg1 [mm]``.

    Raises:
        MeasurementFormatError: the title is not ``name`` or ``name [unit]``.
    """
    m = _COLUMN.match(col)
    if not m:
        raise MeasurementFormatError(f"column name {col!r} is not understood")
    return m.group(1), m.group(2)


def parse_numbers(rows: list[list[str]], columns: list[str], name: str) -> np.ndarray:
    """The data rows as numbers, shape (m, len(columns)).

    Raises:
        MeasurementFormatError: a row with the wrong number of fields.
        BadValueError: a cell that is not a number (names data row and column).
        NonFiniteValueError: a NaN or infinite cell (names data row and column).
    """
    out = np.empty((len(rows), len(columns)))
    for i, row in enumerate(rows, start=1):
        if len(row) != len(columns):
            raise MeasurementFormatError(
                f"{name} data row {i}: {len(row)} fields, the column line has {len(columns)}"
            )
        for j, cell in enumerate(row):
            try:
                v = float(cell)
            except ValueError:
                raise BadValueError(
                    f"{name} data row {i}, column {columns[j]!r}: {cell.strip()!r} is not a number",
                    i,
                    columns[j],
                ) from None
            if not math.isfinite(v):
                raise NonFiniteValueError(
                    f"{name} data row {i}, column {columns[j]!r}: value is {cell.strip()}",
                    i,
                    columns[j],
                )
            out[i - 1, j] = v
    return out


def actuator_columns(actuated: Sequence[str], units: Sequence[str] | None) -> list[str]:
    """Column titles of the actuator columns, with ``[unit]`` when ``units`` is given.

    Raises:
        MeasurementError: ``units`` and ``actuated`` differ in length.
    """
    if units is None:
        return list(actuated)
    if len(units) != len(actuated):
        raise MeasurementError(f"{len(units)} actuator units for {len(actuated)} actuators")
    return [f"{a} [{u}]" for a, u in zip(actuated, units, strict=True)]


def write_csv(
    path: str | Path,
    magic: str,
    header_lines: Iterable[str],
    columns: Sequence[str],
    rows: Iterable[Sequence[str]],
) -> Path:
    """Write a pincal file atomically: magic line, ``# `` header lines, columns, rows.

    Args:
        path: output file.
        magic: the file kind (``measurements``, ``poses``, ``commands``).
        header_lines: ``key: value`` lines (without the ``#``).
        columns: column titles.
        rows: data rows, already formatted as text.

    Returns:
        The written path.
    """
    buf = io.StringIO()
    buf.write(f"# pincal {magic} 1\n")
    for line in header_lines:
        buf.write(f"# {line}\n")
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(columns)
    writer.writerows(rows)
    return atomic_write_text(path, buf.getvalue())
