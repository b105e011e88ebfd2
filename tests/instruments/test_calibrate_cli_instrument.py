"""`pincal simulate --instrument` → `pincal calibrate` → a calibration directory."""

from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.io import read_calibration


@pytest.mark.slow
def test_ballbar_file_calibrates_through_the_cli(tmp_path):
    data = tmp_path / "bar.csv"
    run = CliRunner()
    res = run.invoke(main, ["simulate", "stewart_6ups", "--random", "60", "--errors", "seed:2",
                            "--error-size", "0.3,1", "--instrument", "distance",
                            "--out", str(data)])  # fmt: skip
    assert res.exit_code == 0, res.output
    assert "instrument" in json.loads(data.with_suffix(".truth.json").read_text())
    res = run.invoke(main, ["calibrate", "stewart_6ups", "--data", str(data),
                            "--out", str(tmp_path / "cal"), "--json"])  # fmt: skip
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout)
    cal = read_calibration(tmp_path / "cal")
    assert cal.path == tmp_path / "cal"
    # the pivot absorbs a translation of the whole machine, so it is not compared with
    # the simulated one; the fit must reach the noise (reduced χ² ≈ 1)
    assert sorted(k.split(".")[-1] for k in doc["instruments"]) == [
        "length_offset", "pivot_x", "pivot_y", "pivot_z"]  # fmt: skip
    assert 0.5 < doc["reduced_chi2"] < 2.0
