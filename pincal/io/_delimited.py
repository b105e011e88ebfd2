"""Foreign delimited text tables (instrument and controller exports), read-only.

Not a pincal file: no magic line. Leading blank lines and lines starting with ``#`` are
skipped; the first other line holds the column titles, every following non-blank line is
a data row. A reader that knows titles the table must have (``titles``) takes the first
line holding them all as the title line instead: the lines before it (an export's
preamble: take name, frame rate…) are skipped and counted. The delimiter is a comma,
semicolon or tab (``auto`` picks, in that order of preference, tab, then semicolon, then
comma as found in the title line); the decimal mark is ``.`` or ``,`` (``auto``: ``,``
when the delimiter is not a comma and some cell holds a number written with a decimal
comma). Every message names the file and its 1-based line number.
"""

from __future__ import annotations

import csv
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from pincal._files import read_text
from pincal._yaml import shown
from pincal.errors import (
    BadValueError,
    ColumnError,
    MeasurementError,
    MeasurementFileError,
    MeasurementFormatError,
    ShiftedHeaderError,
    clip,
)
from pincal.io._csv import parse_column
from pincal.io._names import is_decimal

__all__ = ["DELIMITERS", "Table", "parse_mapping", "read_table"]

#: option value → delimiter character
DELIMITERS = {"auto": None, ",": ",", ";": ";", "tab": "\t", "\t": "\t"}
_DECIMAL_COMMA = re.compile(r"^\s*[+-]?\d*,\d+(?:[eE][+-]?\d+)?\s*$")


@dataclass(frozen=True)
class Table:
    """A delimited table as text.

    Attributes:
        name: file name (for messages).
        columns: column titles as written (stripped).
        rows: data rows as text cells.
        lines: 1-based file line number of each data row.
        delimiter: the delimiter used.
        decimal: the decimal mark used (``.`` or ``,``).
        preamble: 1-based file lines skipped before the title line (``titles``).
        hints: messages name the ``--delimiter`` / ``--decimal`` options (a command
            that has them).
    """

    name: str
    columns: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]
    lines: tuple[int, ...]
    delimiter: str
    decimal: str
    preamble: tuple[int, ...] = ()
    hints: bool = False

    def find(self, field: str, aliases: Sequence[str], mapping: Mapping[str, str]) -> int | None:
        """Index of the column holding ``field``: the mapped title, else an alias.

        Titles compare case-insensitively and without a bracketed unit.

        Raises:
            ColumnError: a mapped title that is not in the table.
        """
        bare = [
            parse_column(c)[0].lower() if parsable_title(c) else c.lower() for c in self.columns
        ]
        if field in mapping:
            want = mapping[field].strip().lower()
            for k, (c, b) in enumerate(zip(self.columns, bare, strict=True)):
                if c.lower() == want or b == want:
                    return k
            raise ColumnError(
                f"{self.name}: column {shown(mapping[field])} (mapped to {field!r}) not found; "
                f"columns are {shown(list(self.columns))}",
                missing=[mapping[field]],
            )
        for alias in aliases:
            if alias.lower() in bare:
                return bare.index(alias.lower())
        return None

    def unit(self, k: int) -> str | None:
        """The bracketed unit of column ``k`` (``X [mm]`` → ``mm``), or None."""
        return parse_column(self.columns[k])[1] if parsable_title(self.columns[k]) else None

    def number(self, i: int, k: int) -> float:
        """Cell (row ``i``, column ``k``) as a finite float.

        Raises:
            BadValueError: not a number or not finite (names the file line and column).
        """
        cell = self.rows[i][k].strip()
        text = cell.replace(",", ".") if self.decimal == "," else cell
        v = float(text) if is_decimal(text) else math.nan
        if not math.isfinite(v):
            how = "; set it with --decimal" if self.hints else ""
            raise BadValueError(
                f"{self.name} line {self.lines[i]}, column {shown(self.columns[k])}: "
                f"{shown(cell)} is not a finite number (decimal mark {self.decimal!r}{how})",
                i + 1,
                self.columns[k],
            )
        return v

    def text(self, i: int, k: int) -> str:
        """Cell (row ``i``, column ``k``) stripped.

        Raises:
            BadValueError: the cell is empty.
        """
        cell = self.rows[i][k].strip()
        if not cell:
            raise BadValueError(
                f"{self.name} line {self.lines[i]}, column {shown(self.columns[k])}: empty cell",
                i + 1,
                self.columns[k],
            )
        return cell


def parsable_title(title: str) -> bool:
    """Whether a column title parses as ``name [unit]`` (or a bare name)."""
    try:
        parse_column(title)
    except MeasurementFormatError:
        return False
    return True


def _pick_delimiter(title_line: str) -> str:
    for d in ("\t", ";", ","):
        if d in title_line:
            return d
    return ","


def read_table(
    path: str | Path,
    delimiter: str = "auto",
    decimal: str = "auto",
    *,
    titles: Sequence[str] | None = None,
    hints: bool = False,
) -> Table:
    """Read a delimited export (see the module doc).

    Args:
        path: the file (never modified).
        delimiter: ``auto``, ``,``, ``;`` or ``tab``.
        decimal: ``auto``, ``.`` or ``,``.
        titles: titles the title line holds (any case, a bracketed unit aside): the
            title line is the first line (of the first :data:`PREAMBLE_LINES` + 1) that
            holds them all, else the first line. With ``titles`` the messages name no
            option (the command reading the table has no ``--delimiter``); a row whose
            cell count differs from the title line's is named as a shifted title line.
        hints: messages name ``--delimiter`` and ``--decimal`` (only for a command
            that has them: ``pincal import``).

    Returns:
        The table as text cells with their file line numbers.

    Raises:
        MeasurementError: the file cannot be read or an option is unknown.
        MeasurementFormatError: not UTF-8, no title line, a row with the wrong number
            of fields, a decimal comma with a comma delimiter.
    """
    name = Path(path).name
    if delimiter not in DELIMITERS:
        raise MeasurementError(
            f"delimiter {shown(delimiter)} unknown; use one of {list(DELIMITERS)}"
        )
    if decimal not in ("auto", ".", ","):
        raise MeasurementError(f"decimal mark {shown(decimal)} unknown; use auto, '.' or ','")
    text = read_text(path, "delimited table", error=MeasurementFileError)
    numbered = [(n, ln) for n, ln in enumerate(text.splitlines(), start=1) if ln.strip()]
    while numbered and numbered[0][1].lstrip().startswith("#"):
        numbered.pop(0)
    if not numbered:
        raise MeasurementFormatError(f"{name}: no column title line")
    first = _title_line(numbered, titles, delimiter)
    preamble = tuple(n for n, _ in numbered[:first])
    numbered = numbered[first:]
    delim = DELIMITERS[delimiter] or _pick_delimiter(numbered[0][1])
    parsed = _split(numbered, delim, name)
    columns = tuple(c.strip() for c in parsed[0])
    rows, lines = [], []
    for (n, _), cells in zip(numbered[1:], parsed[1:], strict=True):
        if len(cells) != len(columns):
            if titles is not None:
                raise _shifted(name, numbered[0][0], n, len(columns), len(cells), delim)
            raise MeasurementFormatError(
                f"{name} line {n}: {len(cells)} fields, the title line has {len(columns)} "
                f"(delimiter {delim!r}; "
                + ("set it with --delimiter)" if hints else "give every row one cell per title)")
            )
        rows.append(tuple(cells))
        lines.append(n)
    if decimal == "auto":
        decimal = "."
        if delim != "," and any(_DECIMAL_COMMA.match(c) for r in rows for c in r):
            decimal = ","
    elif decimal == "," and delim == ",":
        raise MeasurementFormatError(f"{name}: a decimal comma needs a ';' or tab delimiter")
    return Table(name, columns, tuple(rows), tuple(lines), delim, decimal, preamble,
                 hints=hints)  # fmt: skip


#: most lines before the title line that a reader given ``titles`` skips
PREAMBLE_LINES = 50


def _title_line(numbered: list[tuple[int, str]], titles: Sequence[str] | None,
                delimiter: str) -> int:  # fmt: skip
    """Index in ``numbered`` of the first line holding every one of ``titles`` (else 0)."""
    if not titles:
        return 0
    want = {t.strip().lower() for t in titles}
    for k, (_, line) in enumerate(numbered[: PREAMBLE_LINES + 1]):
        delim = DELIMITERS[delimiter] or _pick_delimiter(line)
        try:
            cells = next(csv.reader([line], delimiter=delim), [])
        except csv.Error:
            continue
        bare = {(parse_column(c.strip())[0] if parsable_title(c.strip()) else c.strip()).lower()
                for c in cells}  # fmt: skip
        if want <= bare:
            return k
    return 0


def _shifted(name: str, title_at: int, n: int, titles: int, cells: int,
             delim: str) -> ShiftedHeaderError:  # fmt: skip
    """The error of a row whose cell count is not the title line's."""
    more = cells - titles
    if more > 0:
        fix = (f"the title line is shifted against the data, {more} column(s) without a "
               f"title: give every column a title (an untitled column an empty one, e.g. "
               f"{more} extra {delim!r} where the untitled columns are), so that each title "
               "sits above its values")  # fmt: skip
    else:
        fix = (f"{-more} title(s) without values: the title line is shifted against the data, "
               "or the row is cut short; one title per column")  # fmt: skip
    return ShiftedHeaderError(
        f"{name} line {n}: {cells} cells under the {titles} titles of line {title_at} "
        f"(delimiter {delim!r}); {fix}"
    )


def _split(numbered: list[tuple[int, str]], delim: str, name: str) -> list[list[str]]:
    """Cells of each line; a line csv cannot split (a huge cell) is named."""
    try:
        return list(csv.reader([ln for _, ln in numbered], delimiter=delim))
    except csv.Error:
        pass
    out = []
    for n, line in numbered:
        try:
            out.append(next(csv.reader([line], delimiter=delim), []))
        except csv.Error as exc:
            raise MeasurementFormatError(
                f"{name} line {n}: cannot be split into cells ({clip(str(exc))}); is this the "
                "right file?"
            ) from None
    return out


def parse_mapping(spec: str | Mapping[str, str] | None, what: str) -> dict[str, str]:
    """``field=Title,field=Title`` (or a mapping) → {field: title}.

    Raises:
        MeasurementError: an item without ``=`` or a field given twice.
    """
    if spec is None:
        return {}
    if isinstance(spec, Mapping):
        return {str(k): str(v) for k, v in spec.items()}
    out: dict[str, str] = {}
    for item in (s for s in spec.split(",") if s.strip()):
        key, eq, title = item.partition("=")
        if not eq or not key.strip() or not title.strip():
            raise MeasurementError(f"{what}: {shown(item)} is not field=Column")
        if key.strip() in out:
            raise MeasurementError(f"{what}: field {shown(key.strip())} mapped twice")
        out[key.strip()] = title.strip()
    return out
