from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from pincal.cli import main


@pytest.mark.slow
def test_demo_runs_and_writes_calibrated_model(tmp_path):
    out = tmp_path / "out"
    res = CliRunner().invoke(
        main, ["demo", "--poses", "30", "--validation", "20", "--out", str(out)]
    )
    assert res.exit_code == 0, res.output
    assert "calibrated model" in res.output
    report = json.loads((out / "identification.json").read_text())
    after = report["validation_after"]["rms_position_mm"]
    before = report["validation_before"]["rms_position_mm"]
    assert after < before / 20
    assert (out / "calibrated.urdf").is_file() and (out / "calibration.json").is_file()


def test_demo_without_report_improves_the_held_out_accuracy(tmp_path):
    """The demo's claim in the fast lane: the report, the slow part, is left out."""
    out = tmp_path / "out"
    args = ["demo", "--poses", "30", "--validation", "10", "--no-report", "--out", str(out)]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    report = json.loads((out / "identification.json").read_text())
    after = report["validation_after"]["rms_position_mm"]
    assert after < report["validation_before"]["rms_position_mm"] / 20
    assert (out / "calibrated.urdf").is_file() and not (out / "report.html").exists()


def test_info_and_clean_error():
    runner = CliRunner()
    res = runner.invoke(main, ["info", "stewart_6ups", "--preset", "stewart42"])
    assert res.exit_code == 0
    assert "42 parameters, 42 identifiable" in res.output
    res = runner.invoke(main, ["info", "no_such_model"])
    assert res.exit_code == 1
    assert res.output.count("\n") == 1 and "'stewart_6ups'" in res.output
    assert "Traceback" not in res.output


def test_help():
    res = CliRunner().invoke(main, ["--help"])
    assert res.exit_code == 0 and "pincal demo" in res.output


def test_demo_freezes_the_objects_at_exit_instead_of_collecting_them(tmp_path):
    """The demo process ends without Python's last full garbage collection."""
    import subprocess
    import sys

    out = str(tmp_path / "out")
    code = (
        "import atexit, gc, sys\n"
        "atexit.register(lambda: print('frozen', gc.get_freeze_count() > 0))\n"
        "from pincal.cli import main\n"
        "main(['demo', '--poses', '12', '--validation', '5', '--candidates', 'none',"
        f" '--no-report', '--out', {out!r}])\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines()[-1] == "frozen True"


def test_demo_runs_with_the_imported_objects_frozen_and_unfreezes_them(monkeypatch):
    import gc

    import pincal.cli._demo_job as job
    from pincal.errors import PincalError

    seen: list[int] = []

    def fake_run_demo(*args, **kwargs):
        seen.append(gc.get_freeze_count())
        raise PincalError("stop here")

    monkeypatch.setattr(job, "run_demo", fake_run_demo)
    before = gc.get_freeze_count()
    res = CliRunner().invoke(main, ["demo", "--no-report"])
    assert res.exit_code == 1 and "stop here" in res.output
    assert seen and seen[0] > before  # the modules loaded so far were frozen for the run
    assert gc.get_freeze_count() == before  # and unfrozen after it
