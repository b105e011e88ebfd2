"""Weights of real data: the noise is declared, or estimated per block (never unit)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from pincal.errors import NoiseEstimationError, SolverOptionError
from pincal.identification import (
    IdentificationProblem,
    LMOptions,
    identify,
    result_from_dict,
    result_to_dict,
)
from pincal.identification.solvers._noise import variance_components
from pincal.measure import NoiseModel, simulate_measurements
from pincal.model import sample_actuators

NOISE = NoiseModel(position=0.01, orientation=0.02)  # mm, mrad


@pytest.fixture(scope="module")
def noisy(stewart, stewart42):
    """60 poses: ~180 redundant equations per block, so σ̂ scatters by ~5 %."""
    rng = np.random.default_rng(7)
    true = rng.normal(0.0, 0.5e-3, len(stewart42))
    poses = sample_actuators(stewart, 60, rng)
    meas = simulate_measurements(stewart42.apply(stewart, true), poses, NOISE, rng)
    return true, meas


@pytest.fixture(scope="module")
def noisy30(stewart, stewart42, stewart_poses):
    rng = np.random.default_rng(8)
    true = rng.normal(0.0, 0.5e-3, len(stewart42))
    return true, simulate_measurements(stewart42.apply(stewart, true), stewart_poses, NOISE, rng)


def _undeclared(meas):
    return dataclasses.replace(meas, noise=None)


@pytest.fixture(scope="module")
def estimated(stewart, stewart42, noisy):
    """The 60-pose data identified without a noise declaration."""
    return identify(stewart, stewart42, _undeclared(noisy[1]))


def test_estimated_noise_matches_the_simulated_one(stewart, stewart42, noisy, estimated):
    """No noise declared: σ per block within 20 % of the simulated σ, parameter σ within
    20 % of the Cramér–Rao σ of the true noise, reduced χ² = 1."""
    _, meas = noisy
    est = estimated
    known = identify(stewart, stewart42, meas)
    w = est.weighting
    assert w.source == "estimated" and w.converged and w.rounds >= 2, est.message
    assert w.position_std == pytest.approx(1e-5, rel=0.2)
    assert w.orientation_std == pytest.approx(2e-5, rel=0.2)
    assert known.weighting.source == "declared" and known.weighting.rounds == 0
    np.testing.assert_allclose(est.std, known.std, rtol=0.2)
    np.testing.assert_allclose(est.values, known.values, atol=0.5 * known.std.max())
    assert est.reduced_chi2 == pytest.approx(1.0, abs=1e-3)  # VCE: Σ redundancy = N − p
    assert sum(w.redundancy.values()) == pytest.approx(est.n_equations - len(est.std), abs=1e-6)
    assert "noise estimated" in est.message


def test_unit_weights_are_never_used(stewart, stewart42, noisy, estimated):
    """The old behaviour (1 m ≙ 1 rad) fits other values than the estimated weights."""
    _, meas = noisy
    problem = IdentificationProblem(stewart, stewart42, _undeclared(meas))
    assert problem.model.noise_source == "estimate" and not problem.model.known_noise
    est = estimated
    # 1 m / 1 rad declared: every direction is then "weak" (1σ beyond 20 mm / 0.1 rad);
    # unit weights fit them all
    unit_noise = {"position": 1e3, "orientation": 1e3}
    unit = identify(
        IdentificationProblem(stewart, stewart42, meas, noise=unit_noise, weak_bound=None)
    )
    assert np.max(np.abs(est.values - unit.values)) > 0.2 * est.std.min()


def test_noise_argument_overrides_the_file(stewart, stewart42, noisy30):
    _, meas = noisy30
    res = identify(stewart, stewart42, _undeclared(meas), noise={"position": 0.02})
    # a zero (undeclared) orientation σ means: estimate
    assert res.weighting.source == "estimated"
    res = identify(stewart, stewart42, _undeclared(meas), noise=NoiseModel(0.02, 0.04))
    assert res.weighting.source == "declared"
    assert res.weighting.position_std == pytest.approx(2e-5)
    assert res.weighting.orientation_std == pytest.approx(4e-5)
    assert res.reduced_chi2 == pytest.approx(0.25, rel=0.3)  # σ declared twice too large
    with pytest.raises(SolverOptionError, match="noise"):
        identify(IdentificationProblem(stewart, stewart42, meas), noise=NOISE)


def test_weighting_round_trips_through_json(estimated):
    res = estimated
    back = result_from_dict(result_to_dict(res))
    assert back.weighting.source == "estimated"
    assert back.weighting.position_std == res.weighting.position_std
    np.testing.assert_array_equal(back.weighting.whitened, res.weighting.whitened)
    assert result_to_dict(res)["weighting"]["outliers"] == list(res.weighting.outliers)


def test_too_few_redundant_equations_is_a_clear_error(stewart, stewart42, noisy):
    """A block whose equations the fit uses up cannot be estimated."""
    _, meas = noisy
    model = IdentificationProblem(stewart, stewart42, _undeclared(meas)).model
    model = model.with_block_std({"position": 1e-5, "orientation": 1e-5})
    m, k = len(meas), 6
    raw = np.full((m, k), 1e-5)
    J = np.zeros((m * k, m * 3))  # one parameter per orientation equation
    rows = (np.arange(m)[:, None] * k + np.array([3, 4, 5])[None, :]).ravel()
    J[rows, np.arange(m * 3)] = 1.0
    with pytest.raises(NoiseEstimationError, match="orientation noise.*--noise"):
        variance_components(model, raw, J)


@pytest.mark.slow
def test_robust_loss_down_weights_an_outlier(stewart, stewart42, noisy30):
    """A gross outlier (0.3 mm on one pose): huber flags it; the linear fit is pulled."""
    true, meas = noisy30
    positions = meas.positions.copy()
    positions[4] += [3e-4, -2e-4, 1e-4]
    bad = dataclasses.replace(meas, positions=positions)
    linear = identify(stewart, stewart42, bad, "lm")
    robust = identify(stewart, stewart42, bad, "lm", options=LMOptions(loss="huber"))
    assert robust.weighting.loss == "huber" and robust.weighting.f_scale == 1.5
    assert 4 in robust.weighting.downweighted and len(robust.weighting.downweighted) <= 4
    assert 4 in robust.weighting.outliers
    assert linear.weighting.downweighted == ()
    err_l, err_r = np.abs(linear.values - true), np.abs(robust.values - true)
    assert np.sqrt(np.mean(err_r**2)) < 0.5 * np.sqrt(np.mean(err_l**2))
    # the robust noise estimate leaves the outlier out
    est = identify(stewart, stewart42, _undeclared(bad), "lm", options=LMOptions(loss="cauchy"))
    assert est.weighting.position_std == pytest.approx(1e-5, rel=0.25)
    assert 4 in est.weighting.downweighted
    doc = result_to_dict(robust)
    assert doc["weighting"]["downweighted"] == list(robust.weighting.downweighted)


def test_f_scale_is_checked():
    with pytest.raises(SolverOptionError, match="f_scale"):
        LMOptions(loss="huber", f_scale=0.0)
