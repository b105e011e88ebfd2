r"""Names and numbers in pincal CSV files: quoting that reads back exactly, strict numbers.

Joint, frame and target names come from the user's URDF and may hold any character.
A name is written bare when it reads back unchanged that way, otherwise quoted:

* in a header value (``# frame: …``) or a list of names (``# actuated: a b``), a
  quoted name is a JSON string (``"a #1"``, escapes ``\\"`` and ``\\\\``);
* in the column line, a quoted title is a CSV string (``"a [b]" [mm]``, ``""`` for a
  quote), followed by the optional unit outside the quotes.

Names with control characters (newline, tab, …) are refused when writing: no
reader of text tables keeps them. Numbers are plain decimals (``-1.5``, ``2e-3``,
``inf``/``nan`` spelled out); Python's extras (``1_0``, non-ASCII digits) are refused.
"""

from __future__ import annotations

import json
import re
import unicodedata
from collections.abc import Sequence

from pincal.errors import MeasurementFormatError, clip

__all__ = [
    "check_name",
    "column_title",
    "decode_value",
    "is_decimal",
    "is_non_finite",
    "quote_value",
    "quote_words",
    "split_columns",
    "split_words",
    "strip_comment",
]

#: character categories no name may hold: controls, surrogates, line/paragraph separators
_UNWRITABLE = ("Cc", "Cs", "Zl", "Zp")
_JSON_STRING = re.compile(r'"(?:[^"\\]|\\.)*"')
_PLAIN_WORD = re.compile(r'^[^\s"#]+$')
_PLAIN_TITLE = re.compile(r'^[^\s,"#\[\]](?:[^,"#\[\]]*[^\s,"#\[\]])?$')
_DECIMAL = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
_NON_FINITE = re.compile(r"[+-]?(?:nan|inf|infinity)", re.IGNORECASE)


def check_name(name: str, what: str) -> None:
    """Refuse a name that a pincal file cannot hold.

    Args:
        name: the joint, frame or target name.
        what: what it names, for the message ("actuated joint", "frame").

    Raises:
        MeasurementFormatError: the name is empty, not a string or holds a control
            character (newline, tab, …).
    """
    if not isinstance(name, str) or not name:
        raise MeasurementFormatError(
            f"{what} name {clip(name)} cannot be written: a name must be non-empty text"
        )
    bad = next((c for c in name if unicodedata.category(c) in _UNWRITABLE), None)
    if bad is not None:
        raise MeasurementFormatError(
            f"{what} name {clip(name)} cannot be written to a pincal file: it holds the "
            f"control or line-break character U+{ord(bad):04X}; rename it (printable "
            "characters only)"
        )


def quote_value(text: str, what: str) -> str:
    """``text`` as a header value: bare when it reads back unchanged, else a JSON string."""
    check_name(text, what)
    if "#" in text or text != text.strip() or text.startswith('"'):
        return json.dumps(text, ensure_ascii=False)
    return text


def quote_words(words: Sequence[str], what: str) -> str:
    """Names as a space-separated header list (JSON string for names that need it)."""
    out = []
    for w in words:
        check_name(w, what)
        out.append(w if _PLAIN_WORD.match(w) else json.dumps(w, ensure_ascii=False))
    return " ".join(out)


def strip_comment(raw: str) -> str:
    """A header value without its trailing ``# comment`` (a ``#`` inside quotes stays)."""
    k = 0
    while k < len(raw):
        if raw[k] == '"':
            m = _JSON_STRING.match(raw, k)
            if m is None:
                break
            k = m.end()
            continue
        if raw[k] == "#":
            return raw[:k].strip()
        k += 1
    return raw.strip()


def decode_value(value: str, where: str) -> str:
    """A header value as text: a JSON string is decoded, a bare value kept.

    Raises:
        MeasurementFormatError: a quoted value that is not one valid JSON string.
    """
    if not value.startswith('"'):
        return value
    try:
        out, end = json.JSONDecoder().raw_decode(value)
    except ValueError:
        out, end = None, 0
    if not isinstance(out, str) or value[end:].strip():
        raise MeasurementFormatError(
            f'{where}: quoted value {clip(value)} is not one JSON string ("…" with \\" '
            "and \\\\ escapes)"
        )
    return out


def split_words(value: str, where: str) -> list[str]:
    """A header list (``a "b c" d``) as its names.

    Raises:
        MeasurementFormatError: an unterminated quoted name.
    """
    out: list[str] = []
    k = 0
    while k < len(value):
        if value[k].isspace():
            k += 1
            continue
        if value[k] == '"':
            m = _JSON_STRING.match(value, k)
            if m is None:
                raise MeasurementFormatError(f"{where}: unterminated quoted name in {clip(value)}")
            out.append(decode_value(m.group(), where))
            k = m.end()
            continue
        m = re.compile(r"\S+").match(value, k)
        assert m is not None
        out.append(m.group())
        k = m.end()
    return out


def column_title(name: str, unit: str | None, what: str = "column") -> str:
    """The column-line title of ``name`` (quoted when needed) with an optional ``[unit]``."""
    check_name(name, what)
    title = name if _PLAIN_TITLE.match(name) else '"' + name.replace('"', '""') + '"'
    return title if unit is None else f"{title} [{unit}]"


def split_columns(line: str, where: str) -> list[str]:
    """The titles of a column line, quoting kept (for :func:`pincal.io._csv.parse_column`).

    Raises:
        MeasurementFormatError: an unterminated quoted title or text after it.
    """
    titles: list[str] = []
    k, n = 0, len(line)
    while True:
        start = k
        while k < n and line[k] in " \t":
            k += 1
        if k < n and line[k] == '"':
            k += 1
            while True:
                j = line.find('"', k)
                if j < 0:
                    raise MeasurementFormatError(
                        f"{where}: unterminated quoted column title in {clip(line[start:])}"
                    )
                if line.startswith('""', j):
                    k = j + 2
                    continue
                k = j + 1
                break
            end = line.find(",", k)
            end = n if end < 0 else end
            rest = line[k:end].strip()
            if rest and not re.fullmatch(r"\[\s*[A-Za-z]+\s*\]", rest):
                raise MeasurementFormatError(
                    f"{where}: {clip(rest)} after the quoted column title "
                    f"{clip(line[start:k].strip())}; only a unit such as [mm] may follow"
                )
        else:
            end = line.find(",", k)
            end = n if end < 0 else end
        titles.append(line[start:end].strip())
        if end >= n:
            return titles
        k = end + 1


def is_decimal(text: str) -> bool:
    """True for a plain decimal number (``-1.5``, ``.5``, ``2e-3``), spaces around allowed."""
    return _DECIMAL.fullmatch(text.strip()) is not None


def is_non_finite(text: str) -> bool:
    """True for ``nan``, ``inf``, ``-infinity`` … (any case)."""
    return _NON_FINITE.fullmatch(text.strip()) is not None
