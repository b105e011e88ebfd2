"""Plot workers started before the plots are known, so they are ready when they come.

A report's plots are known only at the end of a computation (a calibration), and the
first plot a process draws costs importing matplotlib (≈ 0.3 s). :class:`PlotWorkers`
forks one process when it is made; that process imports matplotlib and loads its font
and PNG encoder (:func:`pincal.report._canvas.warm_up`) on the core the computation
leaves idle, then forks the other workers, which start as warm copies of it.
:meth:`PlotWorkers.render` hands the plots of a :class:`PlotJobs` out one at a time,
the next to whichever worker is free, and returns the files in the order the plots
were added. The calling process never imports matplotlib.

Lifetime: each worker talks to the calling process through its own pipe and exits as
soon as that pipe is closed — by :meth:`PlotWorkers.close` or by the calling process
ending in any way, killed included — so no worker outlives its caller. Workers ignore
Ctrl-C (SIGINT reaches the whole process group; the caller decides). A plot whose
worker died, or that cannot be sent to or loaded by a worker, is drawn in the calling
process. Where ``fork`` is not available, or with one worker, no process is started
and :meth:`PlotWorkers.render` draws in the calling process. The PNG bytes are the
same either way.
"""

from __future__ import annotations

import gc
import logging
import multiprocessing
import os
import pickle
import signal
from collections import deque
from multiprocessing.connection import Connection, wait
from pathlib import Path
from types import TracebackType
from typing import cast

from pincal.errors import ReportError
from pincal.report._render import Job, PlotJobs, draw_job, worker_count

__all__ = ["PlotWorkers"]

_log = logging.getLogger(__name__)
_MAX_WORKERS = 16  # a report has about 15 plots: more workers would only wait


class PlotWorkers:
    """Worker processes for a report's plots, started now and warm by the time they draw.

    Use as a context manager (or call :meth:`close`) around the computation whose
    report they will draw::

        with PlotWorkers(-1) as workers:
            ...  # compute and write the calibration directory
            calibration_report(out, workers=workers)

    Args:
        n_jobs: worker processes, at most 16 (-1 or None: one per CPU; 1: none, the
            plots are drawn in the calling process).

    Raises:
        ReportError: ``n_jobs`` is 0 or below -1.
    """

    def __init__(self, n_jobs: int | None = -1) -> None:
        self.n_workers = worker_count(n_jobs, _MAX_WORKERS)
        self._conns: list[Connection] = []
        self._process: multiprocessing.process.BaseProcess | None = None
        if self.n_workers > 1 and "fork" in multiprocessing.get_all_start_methods():
            context = multiprocessing.get_context("fork")
            pairs = [context.Pipe() for _ in range(self.n_workers)]
            ours, theirs = [a for a, _ in pairs], [b for _, b in pairs]
            process = context.Process(
                target=_lead, args=(theirs, ours), name="pincal-plots", daemon=True
            )
            try:
                process.start()
            except OSError as exc:  # no process to be had: the plots are drawn here
                _log.warning("plot workers not started (%s); drawing the plots here", exc)
                for conn in ours:
                    conn.close()
            else:
                self._process, self._conns = process, ours
            for conn in theirs:
                conn.close()

    @property
    def running(self) -> int:
        """Worker processes this object still talks to (0 when plots are drawn here)."""
        return len(self._conns)

    def render(self, jobs: PlotJobs) -> list[Path]:
        """Draw every plot of ``jobs`` in the workers.

        Returns:
            The written files, in the order the plots were added.

        Raises:
            ReportError: a plot's inputs are malformed (the error of the first such
                plot, raised by the plot function), or a worker's answer is unreadable.
        """
        n = len(jobs.jobs)
        paths: list[Path | None] = [None] * n
        errors: dict[int, BaseException] = {}
        todo, here = deque(range(n)), list[int]()  # ``here``: drawn in this process
        idle, busy = list(self._conns), dict[Connection, int]()
        try:
            while todo or busy:
                while todo and idle:
                    i, conn = todo.popleft(), idle.pop()
                    sent = self._send(conn, jobs, i)
                    if sent == "sent":
                        busy[conn] = i
                    elif sent == "here":  # cannot be sent (e.g. a locally defined function)
                        here.append(i)
                        idle.append(conn)
                    else:  # the worker is gone
                        todo.appendleft(i)
                if not busy:
                    break  # no worker left: the rest is drawn here
                for ready in wait(list(busy)):
                    conn = cast(Connection, ready)
                    i = busy.pop(conn)
                    answer = self._answer(conn, i)
                    if answer is None:  # the worker died on this plot
                        todo.appendleft(i)
                        continue
                    idle.append(conn)
                    kind, value = answer
                    if kind == "done":
                        paths[i] = Path(cast(str, value))
                    elif kind == "here":
                        here.append(i)
                    else:
                        errors[i] = cast(BaseException, value)
        except BaseException:  # e.g. Ctrl-C: a busy worker's answer must not be read later
            for conn in busy:
                self._drop(conn)
            raise
        for i in sorted([*here, *todo]):
            try:
                paths[i] = draw_job(jobs.jobs[i], jobs.scratch)
            except Exception as exc:
                errors[i] = exc
        if errors:
            raise errors[min(errors)]
        return [p for p in paths if p is not None]

    def _send(self, conn: Connection, jobs: PlotJobs, i: int) -> str:
        """Send plot ``i`` to the worker on ``conn``: "sent", "here" (unpicklable), "gone"."""
        try:
            payload = pickle.dumps((jobs.jobs[i], jobs.scratch))
        except Exception:
            return "here"
        try:
            conn.send_bytes(payload)
        except OSError:
            self._drop(conn)
            return "gone"
        return "sent"

    def _answer(self, conn: Connection, i: int) -> tuple[str, object] | None:
        """The answer of the worker on ``conn`` about plot ``i`` (see :func:`_serve`).

        Returns:
            ``(kind, value)``, or None when the worker died (it is dropped).
        """
        try:
            data = conn.recv_bytes()
        except (EOFError, OSError):
            _log.warning("a plot worker ended unexpectedly; drawing plot %d here", i)
            self._drop(conn)
            return None
        try:
            answer = pickle.loads(data)
        except Exception as exc:
            return "error", ReportError(f"the answer of a plot worker is unreadable: {exc}")
        return cast(tuple[str, object], answer)

    def _drop(self, conn: Connection) -> None:
        conn.close()
        self._conns.remove(conn)

    def close(self) -> None:
        """Stop the workers (they exit when their pipe closes); idempotent."""
        for conn in self._conns:
            conn.close()
        self._conns = []
        process, self._process = self._process, None
        if process is not None:
            process.join(0.2)  # idle workers exit at once; one still warming up is stopped
            if process.is_alive():
                process.terminate()
                process.join()

    def __enter__(self) -> PlotWorkers:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        value: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.close()


def _lead(theirs: list[Connection], ours: list[Connection]) -> None:
    """The first worker: warm up, fork the others from the warm state, serve ``theirs[0]``."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    for conn in ours:  # the caller's ends: its exit must read as EOF here
        conn.close()
    try:
        from pincal.report._canvas import warm_up

        warm_up()
    except Exception:  # the plots will report the problem when they are drawn
        _log.debug("plot worker warm-up failed", exc_info=True)
    children = []
    for conn in theirs[1:]:
        pid = os.fork()
        if pid == 0:  # pragma: no cover - runs in the forked worker
            code = 1
            try:
                for other in theirs:
                    if other is not conn:
                        other.close()
                _serve(conn)
                code = 0
            finally:
                os._exit(code)
        children.append(pid)
        conn.close()
    _serve(theirs[0])
    for pid in children:
        os.waitpid(pid, 0)


def _draw_without_collections(job: Job, scratch: bool) -> Path:
    """:func:`draw_job` with the garbage collector paused, then one young collection.

    A plot allocates some 10⁵ short-lived objects, which trigger collections of the
    older generations too (the whole of matplotlib, numpy and pincal) during the
    drawing; collecting only the plot's own objects once afterwards frees the same
    (its figure) for less work: about 10 % less drawing time, measured.
    """
    gc.disable()
    try:
        return draw_job(job, scratch)
    finally:
        gc.enable()
        gc.collect(0)


def _serve(conn: Connection) -> None:
    """Draw the plots received on ``conn`` until it closes.

    Answers ``("done", path)``, ``("error", exception)``, or ``("here", reason)`` when
    the plot cannot be loaded here (e.g. its function was defined after the fork):
    the caller then draws it.
    """
    while True:
        try:
            payload = conn.recv_bytes()
        except (EOFError, OSError):
            return
        try:
            job, scratch = pickle.loads(payload)
        except Exception as exc:
            answer: tuple[str, object] = ("here", f"{type(exc).__name__}: {exc}")
        else:
            try:
                answer = ("done", _draw_without_collections(job, scratch))
            except Exception as exc:
                answer = ("error", exc)
        try:
            data = pickle.dumps(answer)
        except Exception:
            error = answer[1]
            data = pickle.dumps(("error", ReportError(f"{type(error).__name__}: {error}")))
        try:
            conn.send_bytes(data)
        except OSError:
            return
