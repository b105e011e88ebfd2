"""Plots of a report, collected while the sections are assembled and drawn together.

Each plot is an independent matplotlib figure written to its own PNG file, so the
plots of one report can be drawn in parallel worker processes. Workers are forked
from the calling process after it imported matplotlib (they inherit it, so a worker
costs a few milliseconds, not an interpreter start); where ``fork`` is not available
(Windows, macOS) or ``n_jobs`` is 1 the plots are drawn here, one after the other.
The PNG bytes do not depend on ``n_jobs``.
"""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable, Iterator
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pincal.errors import ReportError

__all__ = ["Job", "PlotJobs", "draw_job", "worker_count"]


def worker_count(n_jobs: int | None, tasks: int) -> int:
    """Processes to use for ``tasks`` plots: ``n_jobs`` (-1 or None: every CPU), at most ``tasks``.

    Raises:
        ReportError: ``n_jobs`` is 0 or below -1.
    """
    if n_jobs is None or n_jobs == -1:
        n_jobs = os.cpu_count() or 1
    if not isinstance(n_jobs, int) or isinstance(n_jobs, bool) or n_jobs < 1:
        raise ReportError(f"n_jobs must be a positive integer or -1 (every CPU), got {n_jobs!r}")
    return max(1, min(n_jobs, tasks))


Job = tuple[Callable[..., Path], tuple, dict]


def draw_job(job: Job, scratch: bool = False) -> Path:
    """Call one recorded plot; ``scratch``: write it without fsync (see :class:`PlotJobs`)."""
    function, args, kwargs = job
    if not scratch:
        return function(*args, **kwargs)
    from pincal.report._canvas import scratch_files

    with scratch_files():
        return function(*args, **kwargs)


@dataclass
class PlotJobs:
    """Plot calls recorded by :meth:`add` and drawn by :meth:`render`.

    Attributes:
        jobs: ``(plot function, args, kwargs)`` in the order they were added.
        scratch: the plots go to a private temporary folder that is read back and
            deleted, so they are written without fsync.
    """

    jobs: list[Job] = field(default_factory=list)
    scratch: bool = False

    def add(self, function: Callable[..., Path], *args: Any, path: Path, **kwargs: Any) -> Path:
        """Record ``function(*args, path=path, **kwargs)``; return ``path`` (drawn later)."""
        self.jobs.append((function, args, {"path": path, **kwargs}))
        return Path(path)

    def render(
        self, n_jobs: int | None = 1, progress: Callable[[int, int], None] | None = None
    ) -> list[Path]:
        """Draw every recorded plot, in ``n_jobs`` processes (-1: every CPU).

        ``progress``: optional callback ``(plots drawn, plots)`` after each plot.

        Returns:
            The written files, in the order the plots were added.

        Raises:
            ReportError: a plot's inputs are malformed (raised by the plot function).
        """
        workers = worker_count(n_jobs, len(self.jobs))
        scratch = [self.scratch] * len(self.jobs)
        if workers == 1 or "fork" not in multiprocessing.get_all_start_methods():
            return self._collect(map(draw_job, self.jobs, scratch), progress)
        from pincal.report._canvas import import_matplotlib

        import_matplotlib()  # once here, not once per forked worker
        context = multiprocessing.get_context("fork")
        with ProcessPoolExecutor(workers, mp_context=context) as pool:
            return self._collect(pool.map(draw_job, self.jobs, scratch), progress)

    def _collect(
        self, drawn: Iterator[Path], progress: Callable[[int, int], None] | None
    ) -> list[Path]:
        """The files of ``drawn`` (in order), reporting each to ``progress``."""
        paths: list[Path] = []
        for path in drawn:
            paths.append(path)
            if progress is not None:
                progress(len(paths), len(self.jobs))
        return paths
