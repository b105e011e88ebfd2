"""The quality gate: unit mistakes, outliers, duplicates, singular poses, robust fits."""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin
import pytest

import pincal
from pincal.errors import SolverOptionError
from pincal.identification import (
    GateLimits,
    GaussNewtonOptions,
    LMOptions,
    check_measurements,
    check_quality,
    identify,
)
from pincal.identification._weighting import robust_cost
from pincal.identification.problem._problem import CalibrationProblem
from pincal.identification.results._outcome import SolverOutcome
from pincal.identification.solvers._noise import _robust_progress
from pincal.model import sample_actuators

NOISE = pincal.NoiseModel(0.01, 0.02)


@pytest.fixture(scope="module")
def actual(stewart, stewart42):
    truth = np.random.default_rng(3).normal(0.0, 3e-4, len(stewart42))
    return stewart42.apply(stewart, truth)


@pytest.fixture(scope="module")
def clean(stewart, actual):
    rng = np.random.default_rng(4)
    return pincal.simulate_measurements(actual, sample_actuators(stewart, 40, rng), NOISE, rng)


def _scaled(meas, factor):
    return dataclasses.replace(meas, positions=meas.positions * factor)


@pytest.mark.parametrize("noise", ["declared", "estimated"])
def test_clean_data_pass(stewart, stewart42, clean, noise):
    meas = clean if noise == "declared" else dataclasses.replace(clean, noise=None)
    result = identify(stewart, stewart42, meas)
    verdict = check_quality(result, meas, mech=stewart)
    assert verdict.passed, verdict.reason()
    assert verdict.cause == "" and verdict.outlier_poses == ()
    assert 0.5 < verdict.scale_ratio < 1.5
    assert verdict.to_dict()["passed"] is True


@pytest.mark.parametrize(
    ("factor", "declared", "unit"),
    [(1e3, "m", "mm"), (1e-3, "mm", "m"), (0.1, "mm", "cm"), (1 / 25.4, "mm", "in")],
)
def test_unit_mistakes_are_named_before_fitting(stewart, clean, factor, declared, unit):
    verdict = check_measurements(stewart, _scaled(clean, factor), length_unit=declared)
    assert not verdict.passed
    assert verdict.cause == "units" and verdict.likely_unit == unit
    assert verdict.scale_ratio == pytest.approx(factor, rel=0.05)
    assert f"{unit} declared as {declared}" in verdict.reason()
    assert "--force" in verdict.reason()


@pytest.mark.slow  # ~15 s; the unit-mistake verdict itself is checked fast above
def test_unit_mistake_refused_after_fitting(stewart, stewart42, clean):
    """m declared as mm: the fit ends with parameters moved far beyond the bound."""
    meas = _scaled(clean, 1e-3)
    result = identify(stewart, stewart42, meas)
    verdict = check_quality(result, meas, mech=stewart)
    kinds = {i.kind for i in verdict.refusals}
    assert {"units", "change", "chi2"} <= kinds
    assert verdict.cause == "units"
    # without the data check, the result alone is still refused
    alone = check_quality(result)
    assert not alone.passed and {"change", "chi2"} <= {i.kind for i in alone.refusals}


def test_ten_times_too_small_is_refused(stewart, clean):
    verdict = check_measurements(stewart, _scaled(clean, 0.1), length_unit="mm")
    assert not verdict.passed and "cm declared as mm" in verdict.reason()


@pytest.mark.parametrize("size", [1e-3, pytest.param(5e-3, marks=pytest.mark.slow)])
def test_outliers_refuse_least_squares_and_pass_huber(stewart, stewart42, clean, size):
    bad_poses = [3, 17]  # 5 % of 40
    pos = clean.positions.copy()
    pos[bad_poses, 0] += size
    meas = dataclasses.replace(clean, positions=pos)
    result = identify(stewart, stewart42, meas)
    verdict = check_quality(result, meas, mech=stewart)
    assert not verdict.passed and verdict.cause == "outliers"
    assert set(bad_poses) <= set(verdict.outlier_poses)
    assert "--loss huber" in verdict.reason()
    robust = identify(stewart, stewart42, meas, "lm", options=LMOptions(loss="huber"))
    ok = check_quality(robust, meas, mech=stewart)
    assert ok.passed, ok.reason()
    assert ok.outlier_poses == tuple(bad_poses)
    assert any(w.kind == "outliers" for w in ok.warnings)


def test_outliers_with_estimated_noise_are_flagged(stewart, stewart42, clean):
    pos = clean.positions.copy()
    pos[[5, 30], 1] += 1e-3
    meas = dataclasses.replace(clean, positions=pos, noise=None)
    result = identify(stewart, stewart42, meas)
    assert result.reduced_chi2 == pytest.approx(1.0, rel=0.05)  # σ absorbed them
    verdict = check_quality(result, meas, mech=stewart)
    assert not verdict.passed and {5, 30} <= set(verdict.outlier_poses)


def test_duplicated_rows_are_warned(stewart, stewart42, clean):
    doubled = dataclasses.replace(
        clean,
        q_act=np.repeat(clean.q_act, 2, axis=0),
        positions=np.repeat(clean.positions, 2, axis=0),
        rotations=np.repeat(clean.rotations, 2, axis=0),
    )
    verdict = check_measurements(stewart, doubled)
    assert verdict.passed
    assert verdict.duplicate_rows[:2] == ((1, 0), (3, 2)) and len(verdict.duplicate_rows) == 40
    assert [w.kind for w in verdict.warnings] == ["duplicates"]
    after = check_quality(identify(stewart, stewart42, doubled), doubled, mech=stewart)
    assert "duplicates" in [w.kind for w in after.warnings]


def test_near_singular_pose_is_refused(stewart, stewart42, actual, clean):
    home = stewart.frame_placement(stewart.q_home)
    rot = pin.rpy.rpyToMatrix(0.0, 0.0, np.radians(89.8))  # the 6-UPS' torsion singularity
    row = actual.inverse(pin.SE3(rot @ home.rotation, home.translation), check_limits=False)
    rng = np.random.default_rng(8)
    meas = pincal.simulate_measurements(actual, np.vstack([clean.q_act, row]), NOISE, rng)
    result = identify(stewart, stewart42, meas)
    verdict = check_quality(result, meas, mech=stewart)
    assert not verdict.passed
    assert verdict.singular_poses == (40,) and verdict.cause == "singular pose"
    assert "singular" in verdict.reason()


def test_failed_solver_is_refused(stewart, stewart42, clean):
    # one Gauss–Newton iteration, no lm after it: a solver that stopped unconverged
    opts = GaussNewtonOptions(max_iterations=1, fallback=False)
    result = identify(stewart, stewart42, clean, options=opts)
    assert not result.success
    verdict = check_quality(result, clean, mech=stewart)
    assert "solver" in [i.kind for i in verdict.refusals]
    # an instrument-file fit too, whatever its χ² (it was only warned once)
    strict = check_quality(result, scalar_instrument=True)
    assert "solver" in [i.kind for i in strict.refusals]


def test_parameter_bound_is_an_option(stewart, stewart42, clean):
    result = identify(stewart, stewart42, clean)
    moved = float(np.max(np.abs(result.full_values - result.initial_values)))
    tight = GateLimits(max_length_change=moved / 2, max_angle_change=moved / 2)
    verdict = check_quality(result, clean, mech=stewart, limits=tight)
    assert [i.kind for i in verdict.refusals] == ["change"]
    assert "--max-change" in verdict.reason()
    # an instrument-file fit is bounded alike (it was only warned once)
    strict = check_quality(result, limits=tight, scalar_instrument=True)
    assert [i.kind for i in strict.refusals] == ["change"]
    with pytest.raises(SolverOptionError, match="max_length_change"):
        GateLimits(max_length_change=-1.0)


def test_robust_fit_worse_than_its_start_is_not_success(stewart, stewart42, clean):
    """The criterion itself: an end point worse than the start is never a success."""
    model = CalibrationProblem(stewart, stewart42, clean)
    x0 = np.zeros(len(stewart42))
    bad = x0 + 2e-3  # 2 mm / 2 mrad on every parameter: far worse than the nominal
    _, _, raw = model.evaluate(bad)
    out = SolverOutcome(bad, 5, (1.0,), True, "converged (xtol)")
    judged = _robust_progress(model, x0, bad, raw / model.sigma, "cauchy", 3.0, out)
    assert not judged.success and "ended worse than its start" in judged.message
    good = identify(stewart, stewart42, clean).full_values
    _, _, raw = model.evaluate(good)
    kept = _robust_progress(model, x0, good, raw / model.sigma, "cauchy", 3.0, out)
    assert kept.success
    r = np.array([0.5, 3.0, -10.0])
    assert robust_cost("linear", r, 1.0) == pytest.approx(0.5 * float(r @ r))
    assert robust_cost("cauchy", r, 3.0) == pytest.approx(4.5 * np.sum(np.log1p((r / 3) ** 2)))


@pytest.mark.parametrize("loss", ["huber", "cauchy"])
def test_robust_fits_with_outliers_succeed_and_pass(stewart, stewart42, clean, loss):
    pos = clean.positions.copy()
    pos[[3, 17], 2] += 5e-3
    meas = dataclasses.replace(clean, positions=pos)
    result = identify(stewart, stewart42, meas, "lm", options=LMOptions(loss=loss))
    assert result.success, result.message
    assert check_quality(result, meas, mech=stewart).passed


def test_unregistered_frame_is_named(stewart, stewart42, clean):
    shifted = dataclasses.replace(clean, positions=clean.positions + np.array([0.05, 0.0, 0.0]))
    result = identify(stewart, stewart42, shifted)
    verdict = check_quality(result, shifted, mech=stewart)
    assert "change" in [i.kind for i in verdict.refusals] and verdict.cause == "frame"
    assert verdict.frame_offset == pytest.approx(0.05, abs=2e-3)
    R = pin.rpy.rpyToMatrix(0.0, 0.0, 0.3)
    turned = dataclasses.replace(
        clean,
        positions=clean.positions @ R.T,
        rotations=np.einsum("ij,mjk->mik", R, clean.rotations),
    )
    result = identify(stewart, stewart42, turned)
    verdict = check_quality(result, turned, mech=stewart)
    assert not verdict.passed and verdict.cause == "frame"
    assert verdict.frame_rotation == pytest.approx(0.3, abs=0.02)
    assert "unregistered frame" in verdict.reason()
