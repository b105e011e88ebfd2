"""Reports are drawn in the calling process: the same files as a pool of processes
draws, plot progress reported plot by plot, and no matplotlib before the first plot."""

from __future__ import annotations

import multiprocessing
import re
import shutil
import subprocess
import sys

import pytest

from pincal.cli._demo_job import run_demo
from pincal.report import calibration_report
from pincal.workflow import DemoSettings
from tests.report._identified import identified_directory

forked = pytest.mark.skipif(
    "fork" not in multiprocessing.get_all_start_methods(), reason="pools are forked"
)


@pytest.fixture(scope="module")
def calibration(tmp_path_factory, stewart, stewart42, stewart_poses):
    return identified_directory(tmp_path_factory, stewart, stewart42, stewart_poses, seed=9)


def _headings(markdown: str) -> list[str]:
    return re.findall(r"^#+ .*$", markdown, flags=re.MULTILINE)


@pytest.mark.slow  # ~25 s (a whole demo twice); in-process drawing is checked fast below
@forked
def test_the_demo_report_drawn_in_process_is_the_pooled_one(tmp_path):
    out = tmp_path / "demo"
    settings = DemoSettings(n_poses=24, n_validation=20, candidates="grid:3")
    run_demo(settings, out)  # the plots are drawn in this process
    again = tmp_path / "again"  # the calibration as it was before its report
    shutil.copytree(out, again, ignore=shutil.ignore_patterns("report.*"))
    pooled = calibration_report(again, n_jobs=2)
    here = out / "report.md"
    assert _headings(here.read_text()) == _headings(pooled.markdown.read_text())
    assert len(_headings(here.read_text())) >= 8
    assert here.read_bytes() == pooled.markdown.read_bytes()  # every table and number
    assert pooled.json is not None
    assert (out / "report.json").read_bytes() == pooled.json.read_bytes()
    assert (out / "report.html").read_bytes() == pooled.html.read_bytes()  # PNGs embedded
    assert pooled.html.read_text().count("data:image/png;base64,") >= 9


@pytest.mark.parametrize("n_jobs", [1, pytest.param(2, marks=forked)])
def test_report_progress_counts_every_plot_once(calibration, tmp_path, n_jobs):
    calls: list[tuple[int, int]] = []
    files = calibration_report(
        calibration, tmp_path, n_jobs=n_jobs, progress=lambda k, n: calls.append((k, n))
    )
    plots = files.html.read_text().count("data:image/png;base64,")
    assert calls == [(k, plots) for k in range(1, plots + 1)]


def test_importing_the_report_package_imports_no_matplotlib():
    probe = "import sys, pincal.report; print('matplotlib' in sys.modules)"
    done = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, check=True, timeout=300
    )
    assert done.stdout.split() == ["False"]
