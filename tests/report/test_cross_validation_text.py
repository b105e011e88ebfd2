"""`pincal validate --cv`'s block and JSON record, rendered from the typed summary."""

from __future__ import annotations

import json

import pytest

from pincal.report import cross_validation_text
from pincal.validation import CrossValidationBaseline, CrossValidationSummary

FOLDS = ((0, 3), (1, 4), (2,))


def _pose(beats: bool, model: str = "nominal model") -> CrossValidationSummary:
    base = CrossValidationBaseline(model, 2.5e-3, 6e-3, 2.4e-3)
    return CrossValidationSummary(3, 7, 5, FOLDS, 0.1e-3, 0.2e-3, 0.5e-3, 0.11e-3, base, beats,
                                  gain_mse=6.2e-6, gain_standard_error=1.5e-6)  # fmt: skip


def _sockets() -> CrossValidationSummary:
    base = CrossValidationBaseline("nominal model", 1.2e-3, 2e-3, 1.1e-3, 1.4911e-3, 2.2e-3)
    return CrossValidationSummary(5, 0, 40, FOLDS, 0.01e-3, 0.0217e-3, 0.04e-3, 0.009e-3,
                                  base, True, socket_distance_rms=0.0105e-3,
                                  socket_distance_max=0.0155e-3)  # fmt: skip


def test_pose_record_in_mm_in_its_order():
    doc = _pose(True).to_dict()
    assert list(doc) == ["k", "seed", "poses", "folds", "fit_rms_mm", "held_out_rms_mm",
                         "held_out_max_mm", "fold_fit_rms_mm", "baseline", "gain_mse_mm2",
                         "gain_standard_error_mm2", "beats_baseline", "verdict"]  # fmt: skip
    assert doc["folds"] == [[0, 3], [1, 4], [2]]
    assert doc["held_out_rms_mm"] == pytest.approx(0.2)
    assert doc["gain_mse_mm2"] == pytest.approx(6.2)
    assert doc["baseline"] == pytest.approx({"model": "nominal model", "held_out_rms_mm": 2.5,
                                             "held_out_max_mm": 6.0, "fold_fit_rms_mm": 2.4})
    json.dumps(doc)  # a JSON record


def test_pose_text_and_verdicts():
    text = cross_validation_text(_pose(True))
    lines = text.split("\n")
    assert lines[0] == "" and text.endswith("\n")
    assert lines[1].startswith("cross-validation: 3 folds over 5 poses (seed 7)")
    assert lines[3].split() == ["calibrated", "model", "0.100", "0.110", "0.200", "0.500"]
    assert lines[4].split() == ["nominal", "model", "2.400", "2.500", "6.000"]
    assert "beats the nominal model on held-out poses: 0.200 mm against 2.500 mm" in text
    assert "lower by 6.2 ± 1.5 mm²" in text
    worse = cross_validation_text(_pose(False, "registration only"))
    assert "does NOT beat the registration only" in worse
    assert "(registration only: instrument frame + marker fitted" in worse


def test_socket_record_and_text():
    cv = _sockets()
    doc = cv.to_dict()
    assert "gain_mse_mm2" not in doc
    assert doc["socket_distance_error_rms_mm"] == pytest.approx(0.0105)
    assert list(doc["baseline"])[-2:] == ["socket_distance_error_rms_mm",
                                          "socket_distance_error_max_mm"]  # fmt: skip
    text = cross_validation_text(cv)
    assert "seating RMS " in text.split("\n")[2] and "held-out RMS" not in text
    assert "  calibrated model  RMS 0.0105   max 0.0155" in text
    assert "  nominal model     RMS 1.4911   max 2.2000" in text
    assert text.rstrip().endswith(
        "held-out socket-distance error 0.0105 mm RMS over the folds (the nominal model: "
        "1.4911 mm); held-out seating error 0.0217 mm RMS"
    )
