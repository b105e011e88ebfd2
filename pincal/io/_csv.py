"""The CSV core shared by every pincal file kind.

A pincal file is UTF-8 text (a leading byte-order mark is accepted): a magic line
``# pincal <kind> 1``, header lines ``# key: value`` (repeatable keys are collected in
order; a ``#`` after the value starts a comment), one column line (a bracketed unit is
optional: ``leg1 [mm]``), then the data rows. Blank lines and ``#`` lines between rows
are ignored. Names that would not read back bare are quoted (:mod:`pincal.io._names`).
Cells are plain decimal numbers. Values are written with ``repr`` (the shortest form
that reads back to the same float) and files are replaced atomically (temporary file
+ rename). Files are read through :func:`pincal._files.read_text` (size cap, no
FIFOs or devices).
"""

from __future__ import annotations

import csv
import io
import math
import re
from collections.abc import Iterable, Sequence
from pathlib import Path

import numpy as np

from pincal._files import read_text
from pincal._yaml import shown
from pincal.errors import (
    BadValueError,
    MeasurementError,
    MeasurementFileError,
    MeasurementFormatError,
    NonFiniteValueError,
    clip,
)
from pincal.io._atomic import atomic_write_text
from pincal.io._names import (
    column_title,
    decode_value,
    is_decimal,
    is_non_finite,
    split_columns,
    split_words,
    strip_comment,
)

__all__ = [
    "Header",
    "actuator_columns",
    "file_kind",
    "fmt",
    "header_value",
    "header_words",
    "parse_column",
    "parse_float",
    "parse_numbers",
    "positive_value",
    "read_lines",
    "split_file",
    "write_csv",
]

#: header key → its values in file order (a key may repeat, e.g. ``target``)
Header = dict[str, list[str]]

_COLUMN = re.compile(r"^\s*([^\[\]]+?)\s*(?:\[\s*([A-Za-z]+)\s*\])?\s*$")
_QUOTED_COLUMN = re.compile(r'^\s*"((?:[^"]|"")*)"\s*(?:\[\s*([A-Za-z]+)\s*\])?\s*$')


def fmt(x: float) -> str:
    """``x`` as the shortest text that reads back to the same float."""
    return repr(float(x))


def read_lines(path: str | Path, what: str = "pincal file") -> list[str]:
    """The lines of a UTF-8 text file, read with a size cap (BOM dropped).

    Raises:
        MeasurementFileError: missing, unreadable, a FIFO or device, not UTF-8 (a
            MeasurementFormatError and an InputFileError).
        InputLimitError: larger than the cap.
    """
    return read_text(path, what, error=MeasurementFileError).splitlines()


def file_kind(path: str | Path) -> str | None:
    """The kind of a pincal file (``measurements``, ``poses``…) or None for other text.

    Raises:
        MeasurementFileError: missing, unreadable, a FIFO or device, not UTF-8.
        InputLimitError: larger than the size cap.
    """
    for line in read_lines(path, "data file"):
        s = line.strip()
        if not s:
            continue
        if s.startswith("#") and s[1:].strip().startswith("pincal "):
            return s[1:].split()[1]
        return None
    return None


#: where a pincal file of each kind is read, said when it is given where another is read
_READ_BY = {
    "sockets": " (a socket file is read by `pincal calibrate --data`; a socket calibration "
    "is checked with `pincal validate --cv`)",
    "poses": " (a pose file is read by `pincal simulate --poses` and `pincal compensate "
    "--targets`)",
    "measurements": " (a measurements file is read by `pincal calibrate --data` and "
    "`pincal validate --data`)",
}


def split_file(path: str | Path, magic: str) -> tuple[Header, list[str], list[list[str]]]:
    """Header (key → values, repeated keys collected), column titles, data rows (text).

    Header values keep their quoting (decode with :func:`header_value` or
    :func:`header_words`); column titles too (decode with :func:`parse_column`).

    Args:
        path: the file.
        magic: the expected kind of the first line ``# pincal <magic> 1``.

    Raises:
        MeasurementError: the file cannot be read.
        MeasurementFormatError: not UTF-8, another pincal kind, no magic line, no
            column line, a malformed row (file line named).
        InputLimitError: the file is larger than the size cap.
    """
    lines = read_lines(path, f"{magic} file")
    name = Path(path).name
    header: Header = {}
    body: list[tuple[int, str]] = []
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
                        f"{name} line {n}: this is a {clip(text)} file, expected 'pincal "
                        f"{magic}'{_READ_BY.get(''.join(text.split()[1:2]), '')}"
                    )
                version = text.split()[2:3]
                if version and version != ["1"]:
                    v = version[0]
                    newer = v.isdigit() and int(v) > 1
                    raise MeasurementFormatError(
                        f"{name} line {n}: format version {clip(v)}"
                        + ("; this pincal reads version 1 (upgrade pincal)" if newer
                           else f" is not valid; the first line is '# pincal {magic} 1'")
                    )  # fmt: skip
                seen_magic = True
                continue
            if ":" in text:
                key, _, value = text.partition(":")
                header.setdefault(key.strip().lower(), []).append(strip_comment(value))
            continue
        body.append((n, line))
    if not seen_magic:
        raise MeasurementFormatError(f"{name}: missing the first header line '# pincal {magic} 1'")
    if not body:
        raise MeasurementFormatError(f"{name}: no column line and no data rows")
    columns = split_columns(body[0][1], f"{name} line {body[0][0]}")
    if len(columns) == 1 and (";" in columns[0] or "\t" in columns[0]):
        sep = "';'" if ";" in columns[0] else "tabs"
        raise MeasurementFormatError(
            f"{name} line {body[0][0]}: the columns are separated by {sep}; a pincal "
            f"{magic} file separates them by ',' (with '.' as the decimal point)"
        )
    empty = [k for k, c in enumerate(columns, start=1) if not c.strip()]
    if empty:
        trailing = " (a trailing ',' at the end of the line?)" if empty[-1] == len(columns) else ""
        raise MeasurementFormatError(
            f"{name} line {body[0][0]}: column {empty[0]} of {len(columns)} has no title"
            f"{trailing}; every column needs a title such as x or x [mm]"
        )
    return header, columns, _rows(body[1:], name)


def _rows(body: list[tuple[int, str]], name: str) -> list[list[str]]:
    try:
        return list(csv.reader([ln for _, ln in body], skipinitialspace=True))
    except csv.Error:
        pass
    for n, line in body:  # find the offending line
        try:
            next(csv.reader([line], skipinitialspace=True), [])
        except csv.Error as exc:
            raise MeasurementFormatError(
                f"{name} line {n}: cannot be split into cells ({clip(str(exc))}); a cell holds "
                f"one number (at most {csv.field_size_limit()} characters)"
            ) from None
    raise MeasurementFormatError(f"{name}: cannot be split into cells")  # pragma: no cover


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
    return decode_value(header[key][0], f"{name} header '{key}'")


def header_words(header: Header, key: str, name: str) -> list[str]:
    """The names of list header ``key`` (``# actuated: a "b c"``); [] when absent.

    Raises:
        MeasurementFormatError: given more than once, or a malformed quoted name.
    """
    if key not in header:
        return []
    if len(header[key]) > 1:
        raise MeasurementFormatError(f"{name}: header '{key}' given {len(header[key])} times")
    return split_words(header[key][0], f"{name} header '{key}'")


def parse_float(text: str, where: str) -> float:
    """A plain decimal number (``-1.5``, ``2e-3``; no ``1_0``, no non-ASCII digits).

    Args:
        text: the text.
        where: file and field, for the message.

    Returns:
        The number (may be non-finite for ``inf``/``nan`` or an overflowing exponent;
        callers check).

    Raises:
        MeasurementFormatError: not a plain decimal number.
    """
    if is_decimal(text) or is_non_finite(text):
        return float(text)
    raise MeasurementFormatError(
        f"{where}: {clip(text.strip())} is not a decimal number (write e.g. 12.5 or -1e-3; "
        "no digit separators)"
    )


def positive_value(text: str, key: str, name: str) -> float:
    """Header value ``text`` of ``key`` as a finite number > 0.

    Raises:
        MeasurementFormatError: not a number, not finite or not positive.
    """
    v = parse_float(text, f"{name} header {key!r}")
    if not (math.isfinite(v) and v > 0):
        raise MeasurementFormatError(
            f"{name}: header {key!r} is {clip(text)}; it must be a finite number > 0"
        )
    return v


def parse_column(col: str) -> tuple[str, str | None]:
    """(name, unit or None) of a column title such as ``leg1 [mm]`` or ``"a [b]" [mm]``.

    Raises:
        MeasurementFormatError: the title is not ``name`` or ``name [unit]`` (the name
            quoted when it holds ``,"#[]`` or spaces at its ends).
    """
    q = _QUOTED_COLUMN.match(col)
    if q:
        return q.group(1).replace('""', '"'), q.group(2)
    m = _COLUMN.match(col)
    if not m:
        raise MeasurementFormatError(
            f"column title {clip(col)} is not understood; write name or name [unit] (quote a "
            'name holding [ ] with "…")'
        )
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
        joined = "".join(row)
        # float() also reads 1_0, non-ASCII digits and 0x-free oddities; only rows with an
        # underscore or a non-ASCII character need the (slower) strict check
        strict = "_" in joined or not joined.isascii()
        for j, cell in enumerate(row):
            try:
                v = float(cell)
            except ValueError:
                v = None
            if v is None or (strict and not (is_decimal(cell) or is_non_finite(cell))):
                raise BadValueError(
                    f"{name} data row {i}, column {shown(columns[j])}: {shown(cell.strip())} is "
                    "not a number (write a plain decimal such as 12.5 or -1e-3; no digit "
                    "separators)",
                    i,
                    columns[j],
                )
            if not math.isfinite(v):
                raise NonFiniteValueError(
                    f"{name} data row {i}, column {shown(columns[j])}: value is "
                    f"{shown(cell.strip())}; every cell must be a finite number",
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
        return [column_title(a, None, "actuated joint") for a in actuated]
    if len(units) != len(actuated):
        raise MeasurementError(f"{len(units)} actuator units for {len(actuated)} actuators")
    return [column_title(a, u, "actuated joint") for a, u in zip(actuated, units, strict=True)]


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
        header_lines: ``key: value`` lines (without the ``#``; names quoted with
            :func:`pincal.io._names.quote_value`).
        columns: column titles (names quoted with :func:`pincal.io._names.column_title`).
        rows: data rows, already formatted as text.

    Returns:
        The written path.

    Raises:
        MeasurementFormatError: two columns with the same name.
    """
    names = [parse_column(c)[0] for c in columns]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise MeasurementFormatError(
            f"cannot write {clip(str(path), 300)}: column {clip(twice[0])} would appear twice (a "
            "joint or target named like another column); rename it so column names differ"
        )
    buf = io.StringIO()
    buf.write(f"# pincal {magic} 1\n")
    for line in header_lines:
        buf.write(f"# {line}\n")
    buf.write(",".join(columns) + "\n")
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerows(rows)
    return atomic_write_text(path, buf.getvalue())
