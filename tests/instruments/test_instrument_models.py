"""Instrument measurement models: exact derivatives, joint Jacobian, noise-free recovery."""

from __future__ import annotations

import numpy as np
import pytest

from pincal.errors import MeasurementError, SolverOptionError
from pincal.identification import (
    CalibrationProblem,
    InstrumentProblem,
    identify_instruments,
)
from pincal.measure import (
    INSTRUMENT_KINDS,
    Distance,
    InstrumentData,
    Point,
    Sphere,
    instrument_class,
    simulate_instrument,
    simulate_measurements,
)
from pincal.model import SolverOptions, load_mechanism, parameters
from tests.instruments.conftest import setups


def _fd(f, x, h):
    cols = []
    for k in range(x.size):
        e = np.zeros(x.size)
        e[k] = h
        cols.append((f(x + e) - f(x - e)) / (2 * h))
    return np.stack(cols, axis=-1)


@pytest.mark.parametrize("kind", INSTRUMENT_KINDS)
def test_reading_derivatives_match_central_differences(kind):
    rng = np.random.default_rng(3)
    P = rng.uniform(-0.2, 0.2, (12, 3)) + np.array([0, 0, 0.5])
    inst, theta, ids = setups(P)[kind]
    ids = None if ids is None else np.arange(12) % 2
    _, dp, dth = inst.predict(P, theta, ids)
    for i in range(len(P)):
        num = _fd(
            lambda p, i=i: inst.predict(P[[i]] * 0 + p, theta, None if ids is None else ids[[i]])[
                0
            ],
            P[i],
            1e-6,
        )
        np.testing.assert_allclose(dp[i], num[0], atol=1e-8)
    num_th = _fd(lambda t: inst.predict(P, t, ids)[0], theta, 1e-6)
    np.testing.assert_allclose(dth, num_th, atol=1e-8)


@pytest.mark.parametrize("kind", INSTRUMENT_KINDS)
def test_joint_jacobian_matches_central_differences(
    kind, stewart, stewart42, stewart_rows80, stewart_tool80
):
    rows = stewart_rows80[:10]
    inst, theta, ids = setups(stewart_tool80)[kind]
    ids = None if ids is None else ids[:10]
    data = simulate_instrument(stewart, inst, theta, rows, ids=ids, noise=False)
    prob = InstrumentProblem(stewart, stewart42, [data])
    x = prob.x0 + np.random.default_rng(1).normal(0, 1e-4, prob.x0.size)
    _, J, _ = prob.evaluate(x)
    num = _fd(lambda y: prob.evaluate(y, jacobian=False)[0], x, 1e-6)
    scale = np.abs(J).max()
    assert np.abs(J - num).max() <= 1e-6 * scale
    # the machine part is ∂v/∂p · ∂p/∂x: the instrument part alone is not enough
    assert np.abs(J[:, : len(stewart42)]).max() > 1e-3 * scale


@pytest.mark.parametrize("kind", INSTRUMENT_KINDS)
def test_noise_free_recovery_of_the_identifiable_set(
    kind, stewart, stewart42, stewart_rows80, stewart_tool80
):
    inst, theta, ids = setups(stewart_tool80)[kind]
    if kind == "point":
        # one gauge axis is ill-conditioned on the Stewart (condition ≈ 1.4e6 over these
        # poses): at the default FK tolerance 1e-12 the error floor is ~5e-9, so solve
        # the closures to 1e-14 for this kind
        stewart = load_mechanism("stewart_6ups", options=SolverOptions(tol=1e-14))
        stewart42 = parameters(stewart, "stewart42")
    data0 = simulate_instrument(stewart, inst, theta, stewart_rows80, ids=ids, noise=False)
    prob = InstrumentProblem(stewart, stewart42, [data0])
    ident = prob.analyse()
    assert ident.rank < len(prob.names)  # no scalar instrument sees everything
    base = [stewart42.index(n) for n in ident.base_names if n in stewart42.names]
    truth = np.zeros(len(stewart42))
    truth[base] = np.random.default_rng(7).uniform(-1e-3, 1e-3, len(base))
    data = simulate_instrument(
        stewart42.apply(stewart, truth), inst, theta, stewart_rows80, ids=ids, noise=False
    )
    # exact data: the whole identifiable base, also the directions the declared noise
    # would leave unplaced (held by default, see test_weak_directions_are_held)
    res = identify_instruments(stewart, stewart42, [data], weak_bound=None)
    assert res.result.success, res.result.message
    n = len(stewart42)
    fitted = res.fitted
    err = np.abs(res.values - np.r_[truth, theta])[fitted]
    assert err.max() <= 1e-9, err.max()
    assert set(np.flatnonzero(res.result.identified)) == set(base)
    assert res.result.after.rms_position < 1e-10
    assert list(res.instrument_values()) == [f"{kind}0.{k}" for k in inst.parameter_names]
    assert fitted.size == ident.rank and np.all(fitted[fitted >= n] >= n)


def test_pose_dataset_block_equals_calibration_problem(stewart, stewart42, stewart_poses):
    true = np.random.default_rng(2).normal(0, 3e-4, len(stewart42))
    meas = simulate_measurements(
        stewart42.apply(stewart, true),
        stewart_poses[:8],
        {"position": 0.01, "orientation": 0.02},
        np.random.default_rng(0),
    )
    x = np.random.default_rng(4).normal(0, 1e-4, len(stewart42))
    r1, J1, raw1 = CalibrationProblem(stewart, stewart42, meas).evaluate(x)
    r2, J2, raw2 = InstrumentProblem(stewart, stewart42, [meas]).evaluate(x)
    # raw residuals agree to 1e-15 m; whitened by σ = 1e-5 m that is 1e-10
    np.testing.assert_allclose(raw2[0], raw1, atol=1e-15)
    np.testing.assert_allclose(r2, r1, rtol=1e-12, atol=1e-15 / 1e-5)
    np.testing.assert_allclose(J2, J1, rtol=1e-10, atol=1e-9)


def test_files_of_several_kinds_combine_weighted_by_their_noise(
    stewart, stewart42, stewart_rows80, stewart_tool80
):
    s = setups(stewart_tool80)
    truth = np.random.default_rng(8).uniform(-5e-4, 5e-4, len(stewart42))
    actual = stewart42.apply(stewart, truth)
    rng = np.random.default_rng(9)
    bar, th_bar, _ = s["distance"]
    gauge, th_g, _ = s["point"]
    pos = simulate_measurements(
        actual, stewart_rows80[:12], {"position": 0.005, "orientation": 1}, rng, ("x", "y", "z")
    )
    d1 = simulate_instrument(actual, bar, th_bar, stewart_rows80[12:52], rng)
    d2 = simulate_instrument(actual, gauge, th_g, stewart_rows80[52:], rng)
    prob = InstrumentProblem(stewart, stewart42, [pos, d1, d2], labels=["tracker", "bar", "gauge"])
    assert prob.n_equations == 12 * 3 + 40 + 28
    assert [s.ravel()[0] for s in prob.sigma] == [5e-6, 1e-6, 1e-6]
    joint = prob.analyse().rank
    alone = InstrumentProblem(stewart, stewart42, [d1]).analyse().rank
    assert joint > alone
    res = identify_instruments(
        stewart, stewart42, [pos, d1, d2], labels=["tracker", "bar", "gauge"]
    )
    assert res.result.success
    assert 0.3 < res.result.reduced_chi2 < 2.0  # each block whitened by its own noise
    assert "bar.pivot_x" in res.instrument_values()


def test_bad_inputs_raise_measurement_errors(stewart, stewart42):
    with pytest.raises(MeasurementError, match="unknown instrument kind"):
        instrument_class("laser")
    with pytest.raises(MeasurementError, match="radius"):
        Sphere(radius=0.0)
    with pytest.raises(MeasurementError, match="std"):
        Point(std=0.0)
    with pytest.raises(MeasurementError, match="q_act"):
        InstrumentData(
            Point(), np.zeros((3, 6)), np.zeros(2), stewart.actuated, "effector"
        )
    with pytest.raises(MeasurementError, match="at least one"):
        InstrumentProblem(stewart, stewart42, [])
    with pytest.raises(MeasurementError, match="parameters"):
        Distance().predict(np.zeros((1, 3)) + 1, np.zeros(3))
    data = InstrumentData(
        Point(), np.zeros((1, 6)), np.zeros(1), stewart.actuated, "other"
    )
    with pytest.raises(MeasurementError, match="frame"):
        InstrumentProblem(stewart, stewart42, [data])
    good = InstrumentData(
        Point(),
        np.tile(stewart.actuators_of(stewart.q_home), (3, 1)),
        np.zeros(3),
        stewart.actuated,
        stewart.measured_frame,
    )
    with pytest.raises(SolverOptionError, match="gauss-newton"):
        identify_instruments(stewart, stewart42, [good], method="qpso")
