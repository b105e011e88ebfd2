"""G-code programs of linear moves: the targets they reach, and the program rewritten.

Read: a program of RS274 lines. A *move* is a line with axis words (X Y Z, A B C) while
the motion mode is G0 or G1 (modal: ``G1 X10`` then ``Y5`` moves twice). Axes a line
leaves out keep their last value; X Y Z are lengths in the program's unit (G21 mm, the
default; G20 inch), A B C angles in degrees. Comments ``( … )`` and ``; …`` are skipped.
What this reader cannot follow is refused with the line number: arcs (G2/G3: linearise
them first), incremental distances (G91), coordinate changes (G92, G10, G53) and moves
through a reference point (G28, G30), and a move before every axis it needs is known.

Write: every line that is not a move is kept byte for byte (line endings included); a
move's axis values are replaced where they stand and missing axes appended before the
line's comment, the rest of the line (G word, feed, line number, comment) unchanged.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from pincal.errors import MeasurementFormatError

__all__ = ["GcodeMove", "GcodeProgram", "read_gcode", "write_gcode"]

AXES = ("X", "Y", "Z", "A", "B", "C")
_WORD = re.compile(r"([A-Za-z])\s*([+-]?(?:\d+\.?\d*|\.\d+))")
_REFUSED = {
    2: "an arc (G2): linearise arcs into G1 moves first",
    3: "an arc (G3): linearise arcs into G1 moves first",
    91: "incremental distances (G91): give absolute coordinates (G90)",
    92: "a coordinate offset (G92)",
    10: "a coordinate-system change (G10)",
    53: "machine coordinates (G53)",
    28: "a move through the reference point (G28)",
    30: "a move through the reference point (G30)",
}


@dataclass(frozen=True)
class GcodeMove:
    """One linear move.

    Attributes:
        line: 0-based line index in the program.
        values: every axis value after the move (axes the program has used), in the
            program's units (mm or inch, degrees).
        given: the axes written on the line.
        inch: whether the program is in inches (G20) at this line.
    """

    line: int
    values: dict[str, float]
    given: tuple[str, ...]
    inch: bool


@dataclass
class GcodeProgram:
    """A program's lines (with their endings) and its moves."""

    lines: list[str]
    moves: list[GcodeMove] = field(default_factory=list)


def _code_part(line: str) -> tuple[str, int]:
    """The line with comments blanked (same length), and where the code ends."""
    out, depth, end = [], 0, len(line.rstrip("\r\n"))
    for k, ch in enumerate(line[:end]):
        if depth == 0 and ch == ";":
            end = k
            break
        if ch == "(":
            depth += 1
        out.append(" " if depth else ch)
        if ch == ")" and depth:
            depth -= 1
    code = "".join(out)[:end]
    return code, len(code.rstrip())


def read_gcode(text: str, where: str = "program") -> GcodeProgram:
    """The moves of a program (see the module docstring).

    Raises:
        MeasurementFormatError: a construct the reader cannot follow, named with its
            line number (1-based).
    """
    lines = text.split("\n")
    lines = [ln + "\n" for ln in lines[:-1]] + ([lines[-1]] if lines[-1] else [])
    prog = GcodeProgram(lines)
    mode, inch = None, False
    current: dict[str, float] = {}
    for i, line in enumerate(lines):
        code, _ = _code_part(line)
        words = [(m.group(1).upper(), m.group(2)) for m in _WORD.finditer(code)]
        for letter, num in words:
            if letter != "G":
                continue
            g = float(num)
            if g in (0, 1):
                mode = int(g)
            elif g == 20 or g == 21:
                inch = g == 20
            elif int(g) in _REFUSED and g == int(g):
                raise MeasurementFormatError(
                    f"{where} line {i + 1}: {_REFUSED[int(g)]}; pincal compensates programs "
                    "of G0/G1 moves in absolute coordinates (G90)"
                )
        given = tuple(letter for letter, _ in words if letter in AXES)
        if not given:
            continue
        if mode is None:
            raise MeasurementFormatError(
                f"{where} line {i + 1}: axis words before any G0/G1 motion mode"
            )
        for letter, num in words:
            if letter in AXES:
                current[letter] = float(num)
        prog.moves.append(GcodeMove(i, dict(current), given, inch))
    return prog


def _fmt(value: float, inch: bool, axis: str) -> str:
    digits = 5 if axis in "ABC" else (6 if inch else 4)
    text = f"{value:.{digits}f}"
    return "0." + "0" * digits if text == "-0." + "0" * digits else text


def write_gcode(prog: GcodeProgram, new: dict[int, dict[str, float]]) -> str:
    """The program with the moves of ``new`` (line → axis → value) rewritten.

    Lines not in ``new`` are returned as read, byte for byte.
    """
    out = list(prog.lines)
    by_line = {m.line: m for m in prog.moves}
    for i, values in new.items():
        line, move = prog.lines[i], by_line[i]
        code, end = _code_part(line)
        pieces, last = [], 0
        for m in _WORD.finditer(code):
            letter = m.group(1).upper()
            if letter in values:
                pieces += [line[last : m.start(2)], _fmt(values[letter], move.inch, letter)]
                last = m.end(2)
        missing = [a for a in AXES if a in values and a not in move.given]
        extra = "".join(f" {a}{_fmt(values[a], move.inch, a)}" for a in missing)
        if extra and last < end:
            pieces.append(line[last:end])
            last = end
        pieces += [extra, line[last:]] if extra else [line[last:]]
        out[i] = "".join(pieces)
    return "".join(out)
