"""The quality gate sees a wrong model: χ² p-values, probes, honest outliers and causes."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import pincal
from pincal.errors import UnknownNameError
from pincal.identification import (
    GateLimits,
    check_quality,
    identify,
    instrument_profile,
)
from pincal.identification.gate._fit_issues import changes as _changes
from pincal.identification.gate._misspecification import probe_misspecification
from pincal.identification.gate._outliers import deletion_outliers
from pincal.model import sample_actuators

NOISE = pincal.NoiseModel(0.01, 0.02)


@pytest.fixture(scope="module")
def actual(stewart, stewart42):
    truth = np.random.default_rng(13).uniform(-1e-3, 1e-3, len(stewart42))
    return stewart42.apply(stewart, truth)


@pytest.fixture(scope="module")
def clean(stewart, actual):
    rng = np.random.default_rng(14)
    return pincal.simulate_measurements(actual, sample_actuators(stewart, 40, rng), NOISE, rng)


def _judge(stewart, stewart42, meas, **kw):
    result = identify(stewart, stewart42, meas)
    return result, check_quality(result, meas, mech=stewart, **kw)


def test_clean_data_pass_with_probes_and_chi2_reported(stewart, stewart42, clean):
    _, v = _judge(stewart, stewart42, clean)
    assert v.passed, v.reason()
    assert {b[0] for b in v.chi2_blocks} == {"position", "orientation"}
    assert all(p > 1e-3 for *_, p in v.chi2_blocks)
    assert {p[0] for p in v.probes} >= {"scale", "gains", "drift", "trend:tool z"}
    assert v.noise_source == "declared" and v.to_dict()["chi2_blocks"][0]["dof"] > 50


@pytest.mark.parametrize("fault", ["scale", "gain"])
def test_smooth_model_errors_with_estimated_noise_are_refused(stewart, stewart42, clean, fault):
    """A 1 % instrument scale or leg gain: σ̂ absorbs it; the probe does not."""
    meas = dataclasses.replace(clean, noise=None)
    if fault == "scale":
        meas = dataclasses.replace(meas, positions=meas.positions * 1.01)
    else:
        meas = dataclasses.replace(meas, q_act=meas.q_act / 1.01)
    result, v = _judge(stewart, stewart42, meas)
    assert result.reduced_chi2 == pytest.approx(1.0, rel=1e-3)  # blind to χ² by construction
    assert not v.passed and [i.kind for i in v.refusals] == ["model"]
    assert v.cause == "model or instrument" and v.outlier_poses == ()
    scale = next(p for p in v.probes if p[0] == "scale")
    assert scale[1] > 0.9 and scale[2] < 1e-10
    assert "0.99 % scale" in scale[3] or "1 % scale" in scale[3]
    reason = v.reason()
    assert "explains" in reason and "declared" not in reason


def test_small_scale_with_declared_noise_fails_the_chi2_test(stewart, stewart42, clean):
    meas = dataclasses.replace(clean, positions=clean.positions * 1.001)
    _, v = _judge(stewart, stewart42, meas)
    kinds = [i.kind for i in v.refusals]
    assert "chi2" in kinds
    pos = next(b for b in v.chi2_blocks if b[0] == "position")
    assert pos[1] / pos[2] > 1.5 and pos[3] < 1e-6
    assert "larger than the declared noise" in v.reason()
    # the significance is an option: at p < 1e-300 neither test fires
    strict = GateLimits(chi2_significance=1e-300, probe_significance=1e-300)
    result = identify(stewart, stewart42, meas)
    assert check_quality(result, meas, mech=stewart, limits=strict).passed


@pytest.mark.parametrize("declared", [True, False])
def test_one_outlier_is_named_alone(stewart, stewart42, actual, declared):
    rng = np.random.default_rng(15)
    meas = pincal.simulate_measurements(actual, sample_actuators(stewart, 30, rng), NOISE, rng)
    pos = meas.positions.copy()
    pos[11, 0] += 5e-3
    meas = dataclasses.replace(meas, positions=pos, noise=NOISE if declared else None)
    _, v = _judge(stewart, stewart42, meas)
    assert not v.passed and v.cause == "outliers"
    assert v.outlier_poses == (11,)
    assert "1 of 30 poses are outliers" in v.reason()


def test_estimated_noise_against_an_instrument_profile(stewart, stewart42, actual):
    rng = np.random.default_rng(16)
    q = sample_actuators(stewart, 40, rng)
    noisy = pincal.simulate_measurements(actual, q, pincal.NoiseModel(0.1, 0.2), rng)
    noisy = dataclasses.replace(noisy, noise=None)
    result, v = _judge(stewart, stewart42, noisy, instrument="laser-tracker")
    assert not v.passed and "noise" in [i.kind for i in v.refusals]
    assert v.cause == "instrument or model" and "'laser-tracker' profile" in v.reason()
    assert "declared" not in v.reason()
    assert check_quality(result, noisy, mech=stewart, instrument="motion-capture").passed
    assert check_quality(result, noisy, mech=stewart).passed  # no profile: nothing to judge by
    with pytest.raises(UnknownNameError, match="laser-tracker"):
        instrument_profile("laser")


@pytest.mark.parametrize("declared", [True, False])
def test_solver_refusal_names_the_solver_not_the_noise(stewart, stewart42, clean, declared):
    """An unfinished solve with a fit consistent with the noise says so (issue 22)."""
    meas = clean if declared else dataclasses.replace(clean, noise=None)
    result = identify(stewart, stewart42, meas)
    stopped = dataclasses.replace(result, success=False, message="iteration limit reached")
    v = check_quality(stopped, meas, mech=stewart)
    assert [i.kind for i in v.refusals] == ["solver"] and v.cause == "solver"
    assert "larger than the declared noise" not in v.reason()
    assert ("declared noise" in v.cause_text) == declared
    assert ("estimated from the residuals" in v.cause_text) == (not declared)


def test_registration_unknowns_have_their_own_bound(stewart, stewart42, clean):
    result = identify(stewart, stewart42, clean)
    n = len(result.names)
    names = ("base_frame.tx", "tool_frame.rz", *result.names[2:])
    moved = result.initial_values.copy()
    moved[0], moved[1] = 0.077, 0.5  # a rough registration: 77 mm, 0.5 rad
    fake = dataclasses.replace(result, names=names, full_values=moved,
                               units=("m", "rad", *result.units[2:]))  # fmt: skip
    assert _changes(fake, GateLimits()) == []
    far = moved.copy()
    far[0] = 2.0
    issues = _changes(dataclasses.replace(fake, full_values=far), GateLimits())
    assert [i.kind for i in issues] == ["registration"] and "base_frame.tx" in issues[0].message
    machine = moved.copy()
    machine[n - 1] += 0.05
    issues = _changes(dataclasses.replace(fake, full_values=machine), GateLimits())
    assert [i.kind for i in issues] == ["change"]
    # a joint term's change is said in its own unit, never as a length
    gain = dataclasses.replace(fake, full_values=machine,
                               units=(*fake.units[:-1], "1"))  # fmt: skip
    message = _changes(gain, GateLimits())[0].message
    assert f"{names[-1]}: 5 %" in message and " mm;" not in message.split("worst")[1]


@pytest.mark.parametrize("sigmas, refused", [(2.9, False), (3.1, True), (np.nan, True)])
def test_a_change_beyond_the_bound_refuses_only_beyond_three_sigma(stewart, stewart42, clean,
                                                                  sigmas, refused):
    """Every route: a weakly seen parameter wandering 22 mm within 3σ of its own σ is
    said (a warning naming the σ); a runaway, or a change with no finite σ, refuses."""
    result = identify(stewart, stewart42, clean)
    k = int(np.flatnonzero(np.asarray(result.units) == "m")[0])  # the first length
    moved = result.initial_values.copy()
    moved[k] += 0.022
    std = np.asarray(result.std, dtype=float).copy()
    std[int(np.cumsum(result.identified)[k]) - 1] = 0.022 / sigmas
    fake = dataclasses.replace(result, full_values=moved, std=std)
    issues = _changes(fake, GateLimits())
    assert [(i.kind, i.refuse) for i in issues] == [("change", refused)]
    assert result.names[k] in issues[0].message
    assert ("σ: within 3σ of their own uncertainty" in issues[0].message) == (not refused)


def test_probe_f_test_is_calibrated_and_sees_a_term():
    """Linear model, Gaussian noise: false alarms at the nominal rate; a term is found."""
    rng = np.random.default_rng(0)
    m, k, p = 40, 3, 8
    A = rng.normal(size=(m * k, p))
    term = {"scale": rng.normal(size=(m, k, 1))}
    sigma = np.ones((m, k))
    alarms = 0
    for _ in range(400):
        z = rng.normal(size=m * k)
        z -= A @ np.linalg.lstsq(A, z, rcond=None)[0]
        alarms += probe_misspecification(A, z, term, sigma)[0].p_value < 0.05
    assert 0.02 < alarms / 400 < 0.09
    z = rng.normal(size=m * k) + 2.0 * term["scale"].ravel()
    z -= A @ np.linalg.lstsq(A, z, rcond=None)[0]
    probe = probe_misspecification(A, z, term, sigma)[0]
    size = float(probe.size.split()[1]) / 100  # "a 2.01 % scale of …"
    assert probe.p_value < 1e-10 and probe.explained > 0.5 and size == pytest.approx(2.0, abs=0.3)


def test_deletion_outliers_name_the_bad_pose_only():
    rng = np.random.default_rng(1)
    m, k, p = 30, 6, 40
    A = rng.normal(size=(m, k, p))
    named_clean = 0
    for trial in range(50):
        z = rng.normal(size=(m, k))
        named_clean += len(deletion_outliers(A, z, 1e-3)[0])
        if trial < 10:
            z[7, 0] += 30.0
            assert deletion_outliers(A, z, 1e-3)[0] == (7,)
    assert named_clean <= 2


def test_outliers_on_another_machine_name_no_good_pose():
    """wedge3, noise estimated, two 5 mm outliers: the linearised deletion alone also
    named a good pose (19); the refit without the named poses clears it."""
    from pincal.model import load_mechanism, parameters

    mech = load_mechanism("wedge3")
    ps = parameters(mech, next(iter(mech.presets)))
    rng = np.random.default_rng(0)
    bound = np.array([1e-3 if u == "m" else 1e-2 for u in ps.units])
    actual = ps.apply(mech, rng.uniform(-bound, bound))
    q = sample_actuators(mech, 40, rng)
    meas = pincal.simulate_measurements(actual, q, pincal.NoiseModel(0.01, 0.05), rng)
    pos = meas.positions.copy()
    pos[[4, 22], 0] += 5e-3
    meas = dataclasses.replace(meas, noise=None, positions=pos)
    result = identify(mech, ps, meas)
    v = check_quality(result, meas, mech=mech)
    assert not v.passed and v.cause == "outliers" and v.outlier_poses == (4, 22)
