"""Progress of the CLI's long steps, on stderr only (stdout carries ``--json``).

The library reports progress through optional callbacks — ``progress(done, total)``
for counted work (plots, cycles, candidates, samples), ``progress(iteration, cost)``
for an iterative fit — and never imports tqdm; this module turns those callbacks into
a tqdm bar when stderr is a terminal, and into a few plain lines when it is not (a log
file or a pipe stays readable: no carriage returns, no bar redrawn a hundred times).

    with counted("cycles") as step:
        simulate_cycles(..., progress=step)
    with iterations("identifying") as step:
        identify(..., progress=step)
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import IO, TYPE_CHECKING

if TYPE_CHECKING:  # imported in the call: tqdm only on a terminal
    from tqdm import tqdm

__all__ = ["counted", "iterations"]

#: plain-line mode: one line each time a counted step passes another quarter
_QUARTERS = 4
#: a bar appears, and plain lines of a counted step are written, only once the step
#: has run this long [s]: a quick step stays silent
DELAY = 1.0
#: shortest time between two redraws of a bar [s] (tqdm's default)
MININTERVAL = 0.1


def _stream() -> IO[str]:
    """Where progress goes: the current stderr (looked up at each use)."""
    return sys.stderr


def interactive() -> bool:
    """Whether stderr is a terminal (then progress is a redrawn tqdm bar)."""
    isatty = getattr(_stream(), "isatty", None)
    try:
        return bool(isatty and isatty())
    except ValueError:  # a closed stream
        return False


def _bar(label: str, total: int | None, unit: str) -> tqdm:
    from tqdm import tqdm

    return tqdm(
        total=total, desc=label, unit=unit, file=_stream(), leave=False, delay=DELAY,
        mininterval=MININTERVAL,
        dynamic_ncols=True,
    )  # fmt: skip


def _line(text: str) -> None:
    stream = _stream()
    stream.write(text + "\n")
    stream.flush()


@contextmanager
def counted(label: str, unit: str = "it") -> Iterator[Callable[[int, int], None]]:
    """A ``progress(done, total)`` callback for counted work, shown as ``label``.

    On a terminal: a tqdm bar (removed when the step ends). Otherwise: a line
    ``… label: done/total`` at each quarter of the work. Either only once the step
    has run :data:`DELAY` seconds.
    """
    if interactive():
        bar = _bar(label, None, unit)

        def update(done: int, total: int) -> None:
            if bar.total != total:
                bar.total = total
            bar.update(done - bar.n)

        try:
            yield update
        finally:
            bar.close()
        return
    shown, start = [0], time.monotonic()

    def line(done: int, total: int) -> None:
        quarter = (_QUARTERS * done) // max(total, 1)
        if quarter > shown[0] and time.monotonic() - start >= DELAY:
            shown[0] = quarter
            _line(f"… {label}: {done}/{total}")

    yield line


@contextmanager
def iterations(label: str) -> Iterator[Callable[[int, float], None]]:
    """A ``progress(iteration, cost)`` callback of an iterative fit, shown as ``label``.

    On a terminal: a tqdm counter of the callbacks (a fit that re-estimates the noise
    restarts its iterations) with the latest iteration and cost in its postfix.
    Otherwise one line per iteration, ``… label iteration N: cost C``.
    """
    if interactive():
        bar = _bar(label, None, "iter")

        def update(iteration: int, cost: float) -> None:
            bar.set_postfix_str(f"iteration {iteration}, cost {cost:.6g}", refresh=False)
            bar.update(1)

        try:
            yield update
        finally:
            bar.close()
        return

    def line(iteration: int, cost: float) -> None:
        _line(f"… {label} iteration {iteration}: cost {cost:.6g}")

    yield line
