"""`validate --cv K` of a calibration fitted on scalar instrument readings (a ballbar):
each fold refits machine and instrument on the other readings and predicts its own."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from pincal.cli import main

pytestmark = pytest.mark.slow  # two calibrations and their 4-fold refits (≈ 40 s)


def _run(*args: object) -> str:
    res = CliRunner().invoke(main, [str(a) for a in args])
    assert res.exit_code == 0, res.output + repr(res.exception)
    return res.stdout


def _shifted(src: Path, dst: Path, row: int, by: float) -> None:
    """Copy a pincal instrument file with data row ``row`` (0-based) read ``by`` [m] longer."""
    lines = src.read_text().splitlines()
    first = next(i for i, line in enumerate(lines) if not line.startswith("#")) + 1  # header
    cells = lines[first + row].split(",")
    cells[-1] = repr(float(cells[-1]) + by)
    lines[first + row] = ",".join(cells)
    dst.write_text("\n".join(lines) + "\n")


@pytest.fixture(scope="module")
def ballbar(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("ballbar")
    _run("simulate", "stewart_6ups", "--random", "40", "--seed", "3", "--instrument",
         "distance", "--out", folder / "bb.csv")  # fmt: skip
    return folder / "bb.csv"


def test_cv_of_a_ballbar_calibration_beats_the_registered_instrument(ballbar, tmp_path):
    _run("calibrate", "stewart_6ups", "--data", ballbar, "--out", tmp_path / "cal")
    cv = json.loads(_run("validate", tmp_path / "cal", "--cv", "4", "--json"))["cv"]
    assert cv["poses"] == 40 and sorted(i for f in cv["folds"] for i in f) == list(range(40))
    assert cv["baseline"]["model"] == "instruments only"
    assert cv["beats_baseline"] and cv["held_out_rms_mm"] < cv["baseline"]["held_out_rms_mm"]
    # held out, a reading is predicted no better than the fit of the readings it was in
    assert cv["held_out_rms_mm"] > cv["fold_fit_rms_mm"]


def test_a_held_out_reading_is_predicted_without_itself(ballbar, tmp_path):
    """One reading 2 mm long: the fold holding it out never saw it, so its held-out error
    is ≈ 2 mm. A cross-validation that leaked it into the fits would leave no error
    beyond the whole fit's largest residual, at most fit RMS·√40 ≈ 0.44 mm here (the
    30 parameters absorb it)."""
    bad = tmp_path / "bad.csv"
    _shifted(ballbar, bad, row=7, by=2e-3)
    _run("calibrate", "stewart_6ups", "--data", bad, "--out", tmp_path / "cal", "--force")
    cv = json.loads(_run("validate", tmp_path / "cal", "--cv", "4", "--json"))["cv"]
    assert cv["fit_rms_mm"] * 40**0.5 < 1.0  # the fit with the reading absorbs it
    assert cv["held_out_max_mm"] > 1.9


def test_a_ballbar_calibration_predicts_no_pose_error_it_did_not_observe(ballbar, tmp_path):
    """A ballbar sees distances only: validated on full poses, the absolute position and
    the orientation it never observed keep the nominal error, so no prediction is made
    (it gave 0.77 mm against 1.59 mm achieved on a 3-PRS head)."""
    _run("calibrate", "stewart_6ups", "--data", ballbar, "--out", tmp_path / "cal")
    _run("simulate", "stewart_6ups", "--random", "10", "--seed", "5", "--out",
         tmp_path / "poses.csv")  # fmt: skip
    doc = json.loads(_run("validate", tmp_path / "cal", "--data", tmp_path / "poses.csv",
                          "--json"))  # fmt: skip
    predicted = doc["predicted"]
    assert predicted["model_rms_position_mm"] is None
    assert "do not observe" in predicted["withheld"] and "absolute tool" in predicted["withheld"]
