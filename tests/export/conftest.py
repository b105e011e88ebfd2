"""A UR5 calibration from exact simulated data, shared by the export tests (read only)."""

from __future__ import annotations

from pathlib import Path

import pytest
from click.testing import CliRunner

from pincal.cli import main


@pytest.fixture(scope="module")
def ur5_calibration(tmp_path_factory) -> Path:
    """`pincal simulate ur5 --random 30 --noise 0,0` calibrated with the defaults."""
    tmp = tmp_path_factory.mktemp("ur5")
    meas, cal = tmp / "m.csv", tmp / "cal"
    run = CliRunner().invoke
    sim = run(main, ["simulate", "ur5", "--random", "30", "--noise", "0,0", "--out", str(meas)])
    assert sim.exit_code == 0, sim.output
    res = run(main, ["calibrate", "ur5", "--data", str(meas), "--out", str(cal)])
    assert res.exit_code == 0, res.output
    return cal
