"""`pincal calibrate` says whether its σ are linear, and widens them when they are not."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

import pincal
from pincal.cli import main
from pincal.io import write_measurements
from pincal.model import sample_actuators
from pincal.report import quality_lines


@pytest.fixture(scope="module")
def campaign(stewart, stewart42):
    rng = np.random.default_rng(33)
    actual = stewart42.apply(stewart, rng.uniform(-1e-3, 1e-3, len(stewart42)))
    return pincal.simulate_measurements(
        actual, sample_actuators(stewart, 40, rng), pincal.NoiseModel(0.01, 0.02), rng
    )


def test_a_linear_pose_fit_says_its_sigma_are_the_linearised_ones(tmp_path, campaign):
    path = tmp_path / "m.csv"
    write_measurements(path, campaign, length_unit="mm")
    out = tmp_path / "cal"
    res = CliRunner().invoke(main, ["calibrate", "stewart_6ups", "--data", str(path),
                                    "--out", str(out)])  # fmt: skip
    assert res.exit_code == 0, res.output
    assert "linearisation" not in res.stderr  # no warning
    text = (out / "report.txt").read_text()
    assert "uncertainties: linear over one σ along the 12 most uncertain directions" in text
    unc = json.loads((out / "calibration.json").read_text())["quality"]["uncertainty"]
    assert unc["linear"] is True and unc["directions_failed"] == 0
    assert abs(unc["worst_cost_ratio"] - 1) < 0.05 and unc["worst_jacobian_change"] < 0.05


def test_widened_sigma_are_announced_in_the_report():
    quality = {
        "passed": True,
        "warnings": [{"kind": "linearity", "message": "the fit is not linear over its own "
                      "confidence region: …; the σ reported are widened"}],
        "uncertainty": {"linear": False, "draws": 100, "failed": 0, "seed": 0,
                        "directions_checked": 12, "directions_failed": 2},
    }  # fmt: skip
    lines = quality_lines(quality)
    assert any("warning: the fit is not linear over its own confidence region" in x
               for x in lines)  # fmt: skip
    assert any("the σ above are widened by a parametric bootstrap (100 refits, seed 0)" in x
               for x in lines)  # fmt: skip
