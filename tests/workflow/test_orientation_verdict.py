"""Orientation in the held-out verdict and in the prior's choice (6-D marker bodies).

Hand-made cross-validations: a calibration that predicts positions better but
orientations worse by more, each in units of its own noise σ, does not pass; the prior
of the lowest whitened held-out error is chosen; a cross-validation is stored and read
back exactly (what ``validate --cv`` reuses).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from pincal.identification import QualityVerdict
from pincal.validation import (
    BlockScales,
    CrossValidation,
    HeldOutEvidence,
    compare,
    held_out_verdict,
)
from pincal.workflow import _prior_choice, choose_prior


def _cv(pos_mm, ang_mrad=None, fit_mm=0.1, fit_mrad=1.0) -> CrossValidation:
    e = np.asarray(pos_mm, dtype=float) * 1e-3
    folds = tuple(np.arange(i, e.size, 2) for i in range(2))
    if ang_mrad is None:
        return CrossValidation(folds, e, np.full(2, fit_mm * 1e-3))
    a = np.asarray(ang_mrad, dtype=float) * 1e-3
    return CrossValidation(folds, e, np.full(2, fit_mm * 1e-3), a, np.full(2, fit_mrad * 1e-3))


def test_fit_scales_are_the_fold_fits_noise_per_coordinate():
    s = _cv([1, 1], [1, 1], fit_mm=0.3, fit_mrad=3.0).fit_scales()
    assert s is not None
    assert s.position == pytest.approx(0.3e-3 / np.sqrt(3))
    assert s.orientation == pytest.approx(3e-3 / np.sqrt(3))
    assert _cv([1, 1]).fit_scales() is None  # positions only
    assert _cv([1, 1], [1, 1], fit_mrad=0.0).fit_scales() is None  # exact data


def test_orientation_worse_by_more_than_positions_gain_refuses():
    # positions 0.1 mm better per pose, orientations 2 mrad worse; σ 0.1 mm / 1 mrad
    cal = _cv([0.2, 0.3, 0.2, 0.3], [3, 3, 3, 3.5])
    base = _cv([0.3, 0.4, 0.3, 0.4], [1, 1, 1, 1.2])
    plain = HeldOutEvidence(cal, base, "registration only")
    assert plain.gain[0] > 0 and not plain.whitened  # the positions alone: better
    scales = cal.fit_scales()
    both = HeldOutEvidence(cal, base, "registration only", scales)
    assert both.whitened and both.gain[0] < 0
    g, se, beats = compare(cal, base, scales)
    assert (g, se) == both.gain and not beats
    verdict = held_out_verdict(QualityVerdict(), both, result=None)  # type: ignore[arg-type]
    assert not verdict.passed and verdict.cause == "no held-out benefit"
    assert "orientation" in verdict.refusals[0].message
    doc = verdict.held_out
    assert doc["gain_whitened"] < 0 < doc["gain_mse_mm2"]
    assert doc["whitened_by"]["orientation_mrad"] == pytest.approx(1 / np.sqrt(3))
    # orientation better too: passes, the whitened gain positive
    good = HeldOutEvidence(cal, _cv([0.3, 0.4, 0.3, 0.4], [5, 6, 5, 6]), "r", scales)
    assert held_out_verdict(QualityVerdict(), good, result=None).passed  # type: ignore[arg-type]


def test_the_prior_is_chosen_by_the_whitened_error(monkeypatch):
    # σ 1 mm: positions slightly better, orientation much worse; σ 10 mm: the reverse
    cvs = {1.0: _cv([0.20, 0.20], [4, 4]), 10.0: _cv([0.25, 0.25], [1, 1])}
    monkeypatch.setattr(_prior_choice, "cross_validate",
                        lambda fit, meas, k, seed: cvs[fit])  # fmt: skip
    choice = choose_prior(lambda prior: prior.length * 1e3, [], 2, 0, grid=(1.0, 10.0))
    assert choice.prior is not None and choice.prior.length == pytest.approx(10e-3)
    assert choice.orientation == (4.0, 1.0) and choice.scales is not None
    # positions only: the lowest RMS, as before
    cvs = {1.0: _cv([0.20, 0.20]), 10.0: _cv([0.25, 0.25])}
    choice = choose_prior(lambda prior: prior.length * 1e3, [], 2, 0, grid=(1.0, 10.0))
    assert choice.prior is not None and choice.prior.length == pytest.approx(1e-3)
    assert choice.scales is None and choice.orientation == ()


def test_a_cross_validation_is_recorded_and_read_back_exactly():
    rng = np.random.default_rng(4)
    folds = (np.array([0, 3]), np.array([1, 2, 4]))
    cv = CrossValidation(folds, rng.random(5) * 1e-3, rng.random(2), rng.random(5), rng.random(2))
    back = CrossValidation.from_record(json.loads(json.dumps(cv.to_record())))
    for a, b in zip(
        (cv.held_out, cv.fit_rms, cv.held_out_orientation, cv.fit_orientation_rms),
        (back.held_out, back.fit_rms, back.held_out_orientation, back.fit_orientation_rms),
        strict=True,
    ):
        assert np.array_equal(a, b)
    assert [f.tolist() for f in back.folds] == [f.tolist() for f in folds]
    plain = CrossValidation.from_record(json.loads(json.dumps(_cv([1, 2]).to_record())))
    assert plain.held_out_orientation is None and plain.fit_scales() is None
    assert BlockScales(1e-3, 2e-3).to_dict() == {"position_mm": 1.0, "orientation_mrad": 2.0}
