"""How a running calibration reports its long steps, without printing anything itself.

A fit reports each iteration (``progress(iteration, cost)``), a set of refits each one
done (``progress(done, total)``); :class:`Steps` bundles the callbacks a caller gives:
a line before each long step, a warning as soon as it is found, and a context per
iterative or counted step (the command line shows a bar or a few lines, and closes it
when the step ends). The default reports nothing.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import AbstractContextManager, contextmanager
from dataclasses import dataclass

__all__ = ["Steps"]

#: an iterative fit's callback: (iteration, cost [the fit's weighted squared residual])
IterationCallback = Callable[[int, float], None]
#: counted work's callback: (done, total)
CountCallback = Callable[[int, int], None]


def _ignore(line: str) -> None:
    """Report nothing."""


@contextmanager
def _no_iterations(label: str) -> Iterator[IterationCallback]:
    """A fit's iterations reported nowhere (``label`` unused)."""
    yield lambda iteration, cost: None


@contextmanager
def _no_counts(label: str) -> Iterator[CountCallback]:
    """Counted work reported nowhere (``label`` unused)."""
    yield lambda done, total: None


@dataclass(frozen=True)
class Steps:
    """The callbacks through which a calibration reports its progress.

    Attributes:
        say: called with a line (no prefix) before each long step.
        warn: called with a finding worth a warning when it is found mid-run (a
            warning the run's result does not hold).
        iterations: ``label`` → a context yielding the ``(iteration, cost)`` callback
            of an iterative fit, entered for the fit and left when it ends.
        counted: ``label`` → a context yielding the ``(done, total)`` callback of
            counted work (refits), entered for the work and left when it ends.
    """

    say: Callable[[str], None] = _ignore
    warn: Callable[[str], None] = _ignore
    iterations: Callable[[str], AbstractContextManager[IterationCallback]] = _no_iterations
    counted: Callable[[str], AbstractContextManager[CountCallback]] = _no_counts
