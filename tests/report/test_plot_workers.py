"""Plot workers started before the plots: same report, the caller never imports
matplotlib, errors and dead workers handled, and no worker outlives its caller."""

from __future__ import annotations

import logging
import multiprocessing
import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from pincal.errors import ReportError
from pincal.report import PlotWorkers, calibration_report, plot_convergence
from pincal.report._render import PlotJobs
from tests.report._identified import identified_directory

forked = pytest.mark.skipif(
    "fork" not in multiprocessing.get_all_start_methods(), reason="workers are forked"
)


@pytest.fixture(scope="module")
def calibration(tmp_path_factory, stewart, stewart42, stewart_poses):
    return identified_directory(tmp_path_factory, stewart, stewart42, stewart_poses, seed=8)


def _pid_plot(*, path: Path) -> Path:
    """A 'plot' that records which process drew it."""
    path.write_text(str(os.getpid()))
    return path


def _die_unless_in(caller: int, *, path: Path) -> Path:
    """A 'plot' that kills any process but ``caller`` drawing it."""
    if os.getpid() != caller:
        os._exit(3)
    return _pid_plot(path=path)


def _gone(pid: int) -> bool:
    """The process has exited (a zombie waiting for its parent counts as exited)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except FileNotFoundError:
        return True
    return stat.rsplit(")", 1)[1].split()[0] in ("Z", "X")


def _wait_gone(pids: set[int], seconds: float = 20.0) -> set[int]:
    end = time.monotonic() + seconds
    while time.monotonic() < end and not all(_gone(p) for p in pids):
        time.sleep(0.05)
    return {p for p in pids if not _gone(p)}


def _pid_jobs(folder: Path, count: int) -> PlotJobs:
    jobs = PlotJobs()
    for k in range(count):
        jobs.add(_pid_plot, path=folder / f"{k}.txt")
    return jobs


@forked
def test_workers_give_the_same_report(calibration, tmp_path):
    one = calibration_report(calibration, tmp_path / "one", n_jobs=1)
    with PlotWorkers(2) as workers:
        two = calibration_report(calibration, tmp_path / "two", workers=workers)
        assert workers.running == 2
    assert one.html.read_bytes() == two.html.read_bytes()  # the PNGs are embedded
    assert one.markdown.read_bytes() == two.markdown.read_bytes()
    assert one.json is not None and two.json is not None
    assert one.json.read_bytes() == two.json.read_bytes()
    assert one.html.read_text().count("data:image/png;base64,") >= 9


def _run(code: str) -> str:
    done = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        capture_output=True, text=True, check=True, timeout=300,
    )  # fmt: skip
    return done.stdout


def test_importing_the_report_package_imports_no_matplotlib():
    assert _run("import sys, pincal.report; print('matplotlib' in sys.modules)").split() == [
        "False"
    ]


@pytest.mark.slow
@forked
def test_the_caller_of_the_workers_never_imports_matplotlib(calibration, tmp_path):
    out = _run(
        f"""
        import sys
        from pincal.report import PlotWorkers, calibration_report
        with PlotWorkers(2) as workers:
            files = calibration_report({str(calibration)!r}, {str(tmp_path)!r}, workers=workers)
        print('matplotlib' in sys.modules, files.html.read_text().count('data:image/png'))
        """
    )
    imported, images = out.split()
    assert imported == "False" and int(images) >= 9


@forked
def test_the_plots_are_shared_out_and_the_workers_stay_after_an_error(tmp_path):
    with PlotWorkers(2) as workers:
        bad = PlotJobs()
        bad.add(plot_convergence, [1.0, 0.5], path=tmp_path / "ok.png")
        bad.add(plot_convergence, [1.0, float("nan")], path=tmp_path / "bad.png")
        with pytest.raises(ReportError, match="NaN"):
            workers.render(bad)
        assert (tmp_path / "ok.png").is_file()
        jobs = _pid_jobs(tmp_path, 6)
        paths = workers.render(jobs)
        assert paths == [tmp_path / f"{k}.txt" for k in range(6)]
        drawers = {int(p.read_text()) for p in paths}
        assert len(drawers) == 2 and os.getpid() not in drawers
        assert workers.running == 2


@forked
def test_a_plot_that_cannot_be_sent_is_drawn_here(tmp_path):
    def local_plot(*, path: Path) -> Path:  # not picklable: defined in a function
        return _pid_plot(path=path)

    jobs = PlotJobs()
    here = jobs.add(local_plot, path=tmp_path / "here.txt")
    there = jobs.add(_pid_plot, path=tmp_path / "there.txt")
    with PlotWorkers(2) as workers:
        assert workers.render(jobs) == [here, there]
    assert int(here.read_text()) == os.getpid() != int(there.read_text())


@forked
def test_the_plot_of_a_dead_worker_is_drawn_here(tmp_path, caplog):
    (tmp_path / "more").mkdir()
    jobs = PlotJobs()
    for k in range(3):
        jobs.add(_die_unless_in, os.getpid(), path=tmp_path / f"{k}.txt")
    with PlotWorkers(2) as workers, caplog.at_level(logging.WARNING):
        assert workers.render(jobs) == [tmp_path / f"{k}.txt" for k in range(3)]
        assert workers.running == 0  # both died; later plots are drawn here
        assert workers.render(_pid_jobs(tmp_path / "more", 1))[0].read_text() == str(
            os.getpid()
        )
    assert all(int((tmp_path / f"{k}.txt").read_text()) == os.getpid() for k in range(3))
    assert "ended unexpectedly" in caplog.text


@forked
def test_the_workers_exit_when_closed(tmp_path):
    workers = PlotWorkers(2)
    pids = {int(p.read_text()) for p in workers.render(_pid_jobs(tmp_path, 2))}
    assert len(pids) == 2 and not any(_gone(p) for p in pids)
    workers.close()
    workers.close()  # idempotent
    assert workers.running == 0
    assert _wait_gone(pids) == set()


@forked
def test_the_workers_exit_when_the_caller_is_killed(tmp_path):
    code = f"""
        import os, signal
        from pathlib import Path
        from pincal.report import PlotWorkers
        from pincal.report._render import PlotJobs

        def pid_plot(*, path):
            path.write_text(str(os.getpid()))
            return path

        workers = PlotWorkers(2)
        jobs = PlotJobs()
        for k in range(2):
            jobs.add(pid_plot, path=Path({str(tmp_path)!r}) / f"{{k}}.txt")
        print(*(p.read_text() for p in workers.render(jobs)), flush=True)
        os.kill(os.getpid(), signal.SIGKILL)
        """
    done = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, timeout=300
    )
    assert done.returncode == -9, done.stderr
    pids = {int(p) for p in done.stdout.split()}
    assert len(pids) == 2
    assert _wait_gone(pids) == set()


def test_one_worker_starts_no_process(tmp_path):
    with PlotWorkers(1) as workers:
        assert workers.running == 0
        assert workers.render(_pid_jobs(tmp_path, 2))[1].read_text() == str(os.getpid())


@pytest.mark.parametrize("bad", [0, -2, 1.5])
def test_the_worker_count_is_checked(bad):
    with pytest.raises(ReportError, match="n_jobs"):
        PlotWorkers(bad)


def test_scratch_plots_skip_the_durable_write(tmp_path, monkeypatch):
    def no_fsync(fd: int) -> None:
        raise AssertionError("fsync of a scratch plot")

    monkeypatch.setattr(os, "fsync", no_fsync)
    jobs = PlotJobs(scratch=True)
    jobs.add(plot_convergence, [1.0, 0.5], path=tmp_path / "scratch.png")
    (path,) = jobs.render(1)
    assert path.read_bytes().startswith(b"\x89PNG")
    with pytest.raises(AssertionError, match="fsync"):  # a plot for the user is durable
        plot_convergence([1.0, 0.5], tmp_path / "kept.png")


@pytest.mark.slow
@forked
def test_a_demo_with_a_report_imports_no_plotting_in_the_calling_process(tmp_path):
    out = _run(
        f"""
        import sys
        from pincal.cli._demo_job import DemoSettings, run_demo
        res = run_demo(DemoSettings(n_poses=12, n_validation=5), {str(tmp_path)!r})
        heavy = {{"matplotlib", "meshcat", "scipy", "joblib"}}
        print(sorted(heavy & {{m.split(".")[0] for m in sys.modules}}), len(res.files))
        """
    )
    assert out.split() == ["[]", "7"]
    assert (tmp_path / "report.html").read_text().count("data:image/png;base64,") >= 9


@forked
def test_workers_closed_while_warming_up_stop_at_once():
    before = set(multiprocessing.active_children())
    workers = PlotWorkers(2)
    (leader,) = set(multiprocessing.active_children()) - before
    workers.close()  # at once: the first worker is still importing matplotlib
    assert not leader.is_alive()


@forked
def test_a_plot_the_workers_cannot_load_is_drawn_here(tmp_path, monkeypatch):
    with PlotWorkers(2) as workers:

        def late(*, path: Path) -> Path:  # module-level only after the workers started
            return _pid_plot(path=path)

        late.__name__ = late.__qualname__ = "_late_plot"
        monkeypatch.setattr(sys.modules[__name__], "_late_plot", late, raising=False)
        jobs = PlotJobs()
        path = jobs.add(late, path=tmp_path / "late.txt")
        assert workers.render(jobs) == [path]
        assert int(path.read_text()) == os.getpid()
        assert workers.running == 2  # the workers stay


@forked
def test_an_interrupted_render_drops_the_busy_workers(tmp_path, monkeypatch):
    import pincal.report._workers as module

    def interrupted(conns):
        raise KeyboardInterrupt

    with PlotWorkers(2) as workers:
        with monkeypatch.context() as patch:
            patch.setattr(module, "wait", interrupted)
            with pytest.raises(KeyboardInterrupt):
                workers.render(_pid_jobs(tmp_path, 4))
        assert workers.running == 0  # their pending answers are never read as others'
        paths = workers.render(_pid_jobs(tmp_path, 2))
        assert all(int(p.read_text()) == os.getpid() for p in paths)


@forked
def test_workers_that_cannot_be_started_leave_the_plots_here(tmp_path, monkeypatch, caplog):
    def no_fork(self):
        raise OSError(11, "Resource temporarily unavailable")

    monkeypatch.setattr(multiprocessing.context.ForkProcess, "start", no_fork)
    with caplog.at_level(logging.WARNING), PlotWorkers(2) as workers:
        assert workers.running == 0
        assert workers.render(_pid_jobs(tmp_path, 1))[0].read_text() == str(os.getpid())
    assert "not started" in caplog.text
