"""The report shows the cross-validation of `pincal validate --cv K --out` (issue 23.6)."""

from __future__ import annotations

import json

import pytest

from pincal.errors import ReportError
from pincal.report import calibration_report, campaign_notes
from tests.report._identified import identified_directory

#: the ``cv`` object as `pincal validate --cv 5 --out` writes it (numbers [mm])
CV = {
    "k": 5,
    "seed": 0,
    "poses": 34,
    "folds": [[0, 5], [1, 6], [2, 7], [3, 8], [4, 9]],
    "fit_rms_mm": 2.583,
    "held_out_rms_mm": 4.047,
    "held_out_max_mm": 9.126,
    "fold_fit_rms_mm": 2.502,
    "baseline": {
        "model": "registration only",
        "held_out_rms_mm": 4.785,
        "held_out_max_mm": 9.294,
        "fold_fit_rms_mm": 4.012,
    },
    "beats_baseline": True,
    "verdict": "the calibration beats the registration only on held-out poses",
}


@pytest.fixture(scope="module")
def calibration(tmp_path_factory, stewart, stewart42, stewart_poses):
    return identified_directory(tmp_path_factory, stewart, stewart42, stewart_poses, seed=4)


def test_a_cv_validation_file_gives_the_cross_validation_section(calibration, tmp_path):
    path = tmp_path / "validation.json"
    path.write_text(json.dumps({"calibration": str(calibration), "cv": CV}))
    notes = campaign_notes(validation=path)
    assert notes == {"cross_validation": CV}  # a CV-only file has no held-out block
    files = calibration_report(calibration, tmp_path / "rep", notes=notes)
    md = files.markdown.read_text(encoding="utf-8")
    section = md[md.index("## Cross-validation") :]
    assert "5-fold cross-validation over 34 poses, seed 0" in section
    assert "| calibrated model | 2.583 | 2.502 | 4.047 | 9.126 |" in section
    assert "| registration only | – | 4.012 | 4.785 | 9.294 |" in section
    assert "Verdict: the calibration beats the registration only" in section


def test_a_malformed_cv_object_is_named(calibration, tmp_path):
    bad = {**CV, "held_out_rms_mm": "4 mm"}
    path = tmp_path / "validation.json"
    path.write_text(json.dumps({"cv": bad}))
    with pytest.raises(ReportError, match="cross_validation.held_out_rms_mm"):
        calibration_report(calibration, tmp_path / "rep", notes=campaign_notes(validation=path))
    assert not (tmp_path / "rep").exists()  # nothing written
