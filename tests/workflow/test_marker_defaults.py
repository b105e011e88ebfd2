"""The defaults of a marker calibration: the data settle loss and prior, held-out decides.

Simulated UR5 marker tables (tests/cli/test_markers_cli.py's truth: a capture system
1.2 m away and turned, a marker off the last link, the arm's own errors), and the
held-out judgement on hand-made cross-validations.
"""

from __future__ import annotations

import logging

import numpy as np
import pytest

from pincal.errors import CalibrationDirectoryError
from pincal.identification import QualityIssue, QualityVerdict
from pincal.measure import MarkerSetup
from pincal.model import sample_actuators
from pincal.validation import CrossValidation, HeldOutEvidence, held_out_verdict
from pincal.workflow import PRIOR_GRID, MarkerSettings, calibrate_markers, marker_doc, rebuild
from tests.cli.test_markers_cli import _table, _truth

SETUP = MarkerSetup("wrist_3_link", columns=("mx", "my", "mz"), length_unit="mm")


def _cv(errors_mm) -> CrossValidation:
    e = np.asarray(errors_mm, dtype=float) * 1e-3
    folds = tuple(np.arange(i, e.size, 2) for i in range(2))
    return CrossValidation(folds, e, np.full(2, 1e-3))


def _evidence(calibrated, baseline) -> HeldOutEvidence:
    return HeldOutEvidence(_cv(calibrated), _cv(baseline), "registration only")


def test_held_out_decides_and_probes_become_diagnostics(tmp_path):
    mech, actual = _truth(1e-3)
    q = sample_actuators(mech, 24, np.random.default_rng(3))
    _table(tmp_path / "m.csv", actual, q, 2e-5, 4)
    result = calibrate_markers("ur5", tmp_path / "m.csv", SETUP).fit.result
    probe = QualityIssue("model", True, "model or instrument error suspected: a drift")
    verdict = QualityVerdict(issues=(probe,), cause="model or instrument")
    better = held_out_verdict(verdict, _evidence([1, 2, 1, 2], [3, 3, 3, 3]), result)
    assert better.passed and better.cause == "" and better.held_out["gain_mse_mm2"] > 0
    assert better.warnings[0].kind == "model" and "a diagnostic" in better.warnings[0].message
    worse = held_out_verdict(verdict, _evidence([3, 3, 3, 3], [1, 2, 1, 2]), result)
    assert not worse.passed and worse.cause == "no held-out benefit"
    assert [i.kind for i in worse.refusals] == ["held-out"]
    within = held_out_verdict(
        QualityVerdict(), _evidence([1.5, 2.5, 2, 1.9], [2, 2, 2, 2.1]), result
    )
    assert within.passed and [i.kind for i in within.warnings] == ["held-out"]
    solver = QualityIssue("solver", True, "the solver did not succeed")
    still = held_out_verdict(QualityVerdict(issues=(solver,)), _evidence([1] * 4, [3] * 4),
                             result)  # fmt: skip
    assert not still.passed and still.cause == "solver"


def test_defaults_choose_the_prior_and_stay_least_squares_on_clean_data(tmp_path):
    mech, actual = _truth(1e-3)
    q = sample_actuators(mech, 30, np.random.default_rng(21))
    _table(tmp_path / "m.csv", actual, q, 2e-5, 22)
    run = calibrate_markers("ur5", tmp_path / "m.csv", SETUP)
    assert run.loss == "linear" and run.verdict.passed, run.verdict.reason()
    sigmas = [s for s, _ in run.choice.table]
    assert sigmas == list(PRIOR_GRID)
    best = min(run.choice.table, key=lambda t: t[1])
    assert run.prior is not None and run.prior.length == pytest.approx(best[0] * 1e-3)
    held = run.verdict.held_out
    # 1 mm of errors against 20 µm of noise: the calibration predicts 10× better
    assert held["calibrated"]["held_out_rms_mm"] < 0.1 * held["baseline"]["held_out_rms_mm"]
    doc = marker_doc(run)
    assert doc["loss"] == "linear" and doc["loss_spec"] == "auto" and doc["prior_spec"] == "auto"


def test_outliers_switch_the_loss_to_huber(tmp_path, caplog):
    mech, actual = _truth(1e-3)
    q = sample_actuators(mech, 30, np.random.default_rng(21))
    _table(tmp_path / "m.csv", actual, q, 2e-5, 22)
    lines = (tmp_path / "m.csv").read_text().splitlines()
    for row in (5, 17):  # 8 mm along the marker's x, in the file's mm
        cells = lines[row + 1].split(",")
        cells[4] = repr(float(cells[4]) + 8.0)
        lines[row + 1] = ",".join(cells)
    (tmp_path / "m.csv").write_text("\n".join(lines) + "\n")
    with caplog.at_level(logging.ERROR):
        run = calibrate_markers("ur5", tmp_path / "m.csv", SETUP)
    assert run.loss == "huber"
    assert any("refitted with the huber loss" in n and "5" in n and "17" in n for n in run.notes)
    assert run.verdict.passed, run.verdict.reason()
    assert {5, 17} <= set(run.fit.result.weighting.downweighted)
    fixed = calibrate_markers("ur5", tmp_path / "m.csv", SETUP,
                              MarkerSettings(loss="linear", prior="10,10"))  # fmt: skip
    assert fixed.loss == "linear" and not fixed.choice.chosen
    assert {5, 17} <= set(fixed.verdict.outlier_poses)  # named, whatever else is judged


def test_the_calibration_can_be_rebuilt_for_replay(tmp_path):
    """rebuild refuses a data file changed since the calibration."""
    from click.testing import CliRunner

    from pincal.cli import main
    from pincal.io import read_calibration

    mech, actual = _truth(1e-3)
    q = sample_actuators(mech, 20, np.random.default_rng(7))
    _table(tmp_path / "m.csv", actual, q, 2e-5, 8)
    args = [
        "calibrate",
        "ur5",
        "--link",
        "wrist_3_link",
        "--data",
        str(tmp_path / "m.csv"),
        "--marker-columns",
        "mx,my,mz",
        "--length-unit",
        "mm",
        "--out",
        str(tmp_path / "cal"),
    ]
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 0, r.output
    setup, _, meas = rebuild(read_calibration(tmp_path / "cal"))
    assert setup.columns == ("mx", "my", "mz") and len(meas[0]) == 20
    (tmp_path / "m.csv").write_text((tmp_path / "m.csv").read_text() + "\n")
    with pytest.raises(CalibrationDirectoryError, match="changed since"):
        rebuild(read_calibration(tmp_path / "cal"))
