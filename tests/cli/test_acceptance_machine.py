"""`acceptance --calibrated` warns when it simulates another machine than the calibrated one."""

from __future__ import annotations

from click.testing import CliRunner

from pincal.cli import main


def test_acceptance_names_the_options_of_the_calibrated_machine(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # the manifest records the data path as typed
    run = CliRunner().invoke
    assert run(main, ["simulate", "wedge3", "--random", "30", "--errors", "seed:4",
                      "--error-size", "0.5,5", "--out", "m.csv"]).exit_code == 0  # fmt: skip
    assert run(main, ["calibrate", "wedge3", "--data", "m.csv", "--out", "cal"]).exit_code == 0
    other = run(main, ["acceptance", "wedge3", "--calibrated", "cal", "--cycles", "3"])
    assert other.exit_code == 0, other.output
    assert "not the one the calibration was fitted on" in other.output
    assert "--errors seed:4 --params patent --error-size 0.5,5" in other.output
    same = run(main, ["acceptance", "wedge3", "--calibrated", "cal", "--cycles", "3",
                      "--errors", "seed:4", "--error-size", "0.5,5"])  # fmt: skip
    assert same.exit_code == 0, same.output
    assert "not the one the calibration" not in same.output
