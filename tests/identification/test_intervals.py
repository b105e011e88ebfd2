"""Intervals with an estimated noise use Student-t / F quantiles; which covariance is written."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy import stats

import pincal
from pincal.identification import (
    covariance_kind,
    identify,
    interval_quantiles,
    prediction_covariance,
    result_intervals,
)
from pincal.model import sample_actuators


def test_declared_noise_uses_normal_and_chi2_quantiles():
    iv = interval_quantiles(42, {"position": 11.7, "orientation": 6.3}, estimated=False)
    assert not iv.estimated and iv.dof is None
    assert iv.each == pytest.approx(stats.norm.ppf(0.975), rel=1e-12)
    assert iv.joint == pytest.approx(stats.chi2.ppf(0.95, 42), rel=1e-12)
    assert iv.describe() == ""


def test_estimated_noise_uses_student_t_and_f_on_the_smallest_block_redundancy():
    iv = interval_quantiles(42, {"position": 11.7, "orientation": 6.3}, estimated=True)
    assert iv.estimated and iv.dof == pytest.approx(6.3)
    assert iv.each == pytest.approx(stats.t.ppf(0.975, 6.3), rel=1e-12)
    assert iv.joint == pytest.approx(42 * stats.f.ppf(0.95, 42, 6.3), rel=1e-12)
    assert iv.each > 2.3 and iv.joint > 2 * stats.chi2.ppf(0.95, 42)  # far from ±2σ / χ²
    assert iv.approximate and "approximate below ν = 30" in iv.describe()
    d = iv.to_dict()
    assert d["quantile"] == "student-t / F" and d["dof"] == pytest.approx(6.3)
    many = interval_quantiles(6, {"position": 500.0}, estimated=True)
    assert not many.approximate and many.each == pytest.approx(stats.t.ppf(0.975, 500))


def test_a_fit_with_estimated_noise_on_ten_poses_gets_student_t(stewart, stewart42):
    rng = np.random.default_rng(5)
    actual = stewart42.apply(stewart, rng.uniform(-5e-4, 5e-4, len(stewart42)))
    meas = pincal.simulate_measurements(actual, sample_actuators(stewart, 10, rng),
                                        pincal.NoiseModel(0.01, 0.02), rng)  # fmt: skip
    meas = dataclasses.replace(meas, noise=None)
    result = identify(stewart, stewart42, meas)
    assert result.weighting is not None and result.weighting.source == "estimated"
    iv = result_intervals(result, declared=False)
    nu = min(result.weighting.redundancy.values())
    assert iv.dof == pytest.approx(nu) and nu < 30
    assert iv.each == pytest.approx(stats.t.ppf(0.975, nu), rel=1e-12)
    assert iv.joint == pytest.approx(iv.k * stats.f.ppf(0.95, iv.k, nu), rel=1e-12)


@pytest.mark.parametrize(
    ("unc", "source", "kind"),
    [
        ({"method": "linear"}, "declared", "cramer-rao"),
        ({"method": "linear"}, "per-pose", "cramer-rao"),
        ({"method": "linear"}, "estimated", "linear"),
        ({"method": "inflated"}, "declared", "inflated"),
        ({"method": "second-order"}, "declared", "second-order"),
        ({"linear": False, "draws": 100}, "declared", "bootstrap-widened"),  # older pincal
        (None, "declared", "cramer-rao"),
    ],
)
def test_the_covariance_is_called_cramer_rao_only_when_linear_at_declared_noise(unc, source,
                                                                                kind):  # fmt: skip
    notes = {} if unc is None else {"quality": {"uncertainty": unc}}
    assert covariance_kind(notes, source) == kind



@pytest.mark.parametrize(("source", "kind"), [("declared", "cramer-rao"), ("estimated", "linear")])
def test_a_prediction_propagates_the_linear_covariance_of_a_widened_one(source, kind):
    written, linear = np.diag([4.0, 9.0]), np.diag([1.0, 2.0])
    notes = {"quality": {"uncertainty": {"method": "inflated",
                                         "linear_covariance": linear.tolist()}}}  # fmt: skip
    cov, got = prediction_covariance(notes, written, source)
    assert got == kind
    assert np.array_equal(cov, linear)


def test_without_a_recorded_linear_covariance_the_written_one_is_propagated():
    written = np.diag([4.0, 9.0])
    old = {"quality": {"uncertainty": {"method": "inflated"}}}  # an older record
    cov, kind = prediction_covariance(old, written, "declared")
    assert (kind, np.array_equal(cov, written)) == ("inflated", True)
    bad = {"quality": {"uncertainty": {"method": "inflated", "linear_covariance": [[1.0]]}}}
    cov, kind = prediction_covariance(bad, written, "declared")  # not this record's shape
    assert (kind, np.array_equal(cov, written)) == ("inflated", True)
    cov, kind = prediction_covariance({}, written, "declared")
    assert (kind, np.array_equal(cov, written)) == ("cramer-rao", True)


@pytest.mark.slow
def test_a_parallel_bootstrap_rebuilds_the_problem_and_gives_the_serial_sigma(stewart, stewart42):
    from pincal.identification import bootstrap_covariance, pose_recipe, pose_residual_model
    from pincal.identification.uncertainty._bootstrap import _worker

    rng = np.random.default_rng(8)
    actual = stewart42.apply(stewart, rng.uniform(-5e-4, 5e-4, len(stewart42)))
    meas = pincal.simulate_measurements(actual, sample_actuators(stewart, 20, rng),
                                        pincal.NoiseModel(0.01, 0.02), rng)  # fmt: skip
    result = identify(stewart, stewart42, meas)
    problem = pose_residual_model(result, stewart, meas)
    recipe = pose_recipe(result, stewart, meas)
    assert problem is not None and recipe is not None
    x, free = result.full_values, np.flatnonzero(result.identified)
    r0 = np.asarray(problem.evaluate(x)[0])
    # the rebuilt problem gives the caller's residual: its share is refitted there
    assert _worker(recipe, x, free, r0, np.zeros((1, r0.size)) - r0) is not None
    serial = bootstrap_covariance(problem, x, free, draws=4, seed=3)
    parallel = bootstrap_covariance(problem, x, free, draws=4, seed=3, n_jobs=2, factory=recipe)
    assert serial.draws == parallel.draws == 4
    np.testing.assert_allclose(parallel.covariance, serial.covariance, rtol=1e-6, atol=1e-16)
