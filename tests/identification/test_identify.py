"""Identification recovers known errors; uncertainty matches the Cramér–Rao bound."""

from __future__ import annotations

import numpy as np
import pytest

import pincal
from pincal.identification import identify
from pincal.measure import (
    Measurements,
    NoiseModel,
    simulate_measurements,
)
from pincal.model import parameters
from pincal.sensitivity import identification_jacobian


def true_errors(params, rng, std=0.5e-3):
    return rng.normal(0.0, std, len(params))


@pytest.mark.parametrize("method", ["gauss-newton", "lm"])
def test_noise_free_recovery_to_1e9(stewart, stewart42, stewart_poses, method):
    rng = np.random.default_rng(1)
    true = true_errors(stewart42, rng)
    meas = simulate_measurements(stewart42.apply(stewart, true), stewart_poses)
    res = identify(stewart, stewart42, meas, method)
    assert res.success, res.message
    assert np.max(np.abs(res.values - true)) <= 1e-9
    assert res.after.max_position <= 1e-11
    assert res.before.max_position > 1e-4


def test_position_only_recovery(stewart, stewart42, stewart_poses):
    """Position-only data lose 3 parameters; the base set still predicts exactly."""
    rng = np.random.default_rng(2)
    actual = stewart42.apply(stewart, true_errors(stewart42, rng))
    meas = simulate_measurements(actual, stewart_poses, components=("x", "y", "z"))
    assert meas.rotations is None
    res = identify(stewart, stewart42, meas)
    assert res.success and len(res.fixed) == 3, res.fixed
    assert np.isnan(res.after.rms_orientation)
    fresh = pincal.sample_actuators(stewart, 10, np.random.default_rng(9))
    errors = pincal.pose_errors(res.calibrated, actual, fresh)
    assert errors.position.max() <= 1e-9


@pytest.mark.slow
def test_monte_carlo_matches_cramer_rao(stewart, stewart42, stewart_poses):
    """Mean squared parameter error over 100 noisy runs within 0.8–1.25 of tr(CRB)."""
    noise = NoiseModel(position=0.01, orientation=0.02)
    rng = np.random.default_rng(2024)
    true = true_errors(stewart42, rng)
    actual = stewart42.apply(stewart, true)
    clean = simulate_measurements(actual, stewart_poses)
    J = identification_jacobian(stewart, stewart42, stewart_poses, true)
    w = 1.0 / noise.std(clean.components)
    Jw = (J.reshape(len(stewart_poses), 6, -1) * w[None, :, None]).reshape(J.shape)
    crb = np.trace(np.linalg.inv(Jw.T @ Jw))
    sq = []
    for _ in range(100):
        meas = simulate_measurements(actual, stewart_poses, noise, rng)
        res = identify(stewart, stewart42, meas)
        sq.append(np.sum((res.values - true) ** 2))
    ratio = np.mean(sq) / crb
    assert 0.8 <= ratio <= 1.25, ratio


def test_too_few_poses(stewart, stewart42, stewart_poses):
    meas = simulate_measurements(stewart, stewart_poses[:6])
    with pytest.raises(pincal.errors.TooFewPosesError, match="36 equations for 42 parameters"):
        identify(stewart, stewart42, meas)


def test_unidentifiable_refused_or_reduced(stewart, stewart_poses):
    params = parameters(stewart, ["leg1_u1.tx", "leg1_u1.rz", "leg1_slide.offset"])
    meas = simulate_measurements(stewart, stewart_poses)
    with pytest.raises(pincal.UnidentifiableError, match="leg1_u1.rz is not identifiable"):
        identify(stewart, params, meas, reduce=False)
    res = identify(stewart, params, meas)
    assert res.fixed == ("leg1_u1.rz",)
    assert "base parameters" in res.message


def test_measurement_validation(stewart, stewart_poses):
    meas = simulate_measurements(stewart, stewart_poses[:3])
    bad = meas.positions.copy()
    bad[1, 2] = np.nan
    with pytest.raises(pincal.MeasurementError, match="NaN or inf in pose 1"):
        Measurements(meas.q_act, bad, meas.rotations, meas.components, meas.frame, meas.actuated)
    with pytest.raises(pincal.MeasurementError, match="'position' \\[mm\\]"):
        NoiseModel.from_spec({"pos": 0.01})


def test_covariance_and_chi2(stewart, stewart42, stewart_poses):
    rng = np.random.default_rng(8)
    noise = {"position": 0.01, "orientation": 0.02}
    meas = simulate_measurements(
        stewart42.apply(stewart, true_errors(stewart42, rng)), stewart_poses, noise, rng
    )
    res = identify(stewart, stewart42, meas)
    assert res.covariance.shape == (42, 42)
    assert np.allclose(res.std, np.sqrt(np.diag(res.covariance)))
    assert 0.6 < res.reduced_chi2 < 1.5
