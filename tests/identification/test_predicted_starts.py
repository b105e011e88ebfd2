"""First-order predicted warm starts of the closed-loop solves (identification speed).

The prediction ``dq_u = −(∂c/∂q_u)⁻¹ ∂c/∂p · δ`` is only a start guess: the solve from it
must land on the same configuration as a cold solve from home (home's branch), its
closure residual must be second order in δ, and Gauss–Newton's identified values must
not change when the solves start from it.
"""

from __future__ import annotations

import numpy as np
import pytest

import pincal
from pincal.identification.problem import _pose_configurations, _problem
from pincal.identification.problem._pose_configurations import PoseConfigurations
from pincal.model import Mechanism
from pincal.sensitivity._jacobian import jacobian_plan
from pincal.sensitivity.batch import _batch_predict
from pincal.sensitivity.batch._batch_jacobian import param_twists
from pincal.sensitivity.batch._batch_predict import predict_configurations

MODELS = [
    ("stewart_6ups", "stewart42"),
    ("hexaslide_6pus", "pus54"),
    ("pkm5", "hinges24"),
    ("wedge3", "patent"),
]


def _residual(mech: Mechanism, Q: np.ndarray) -> float:
    r, _ = mech.closure_terms_batch(mech.batch_model.kinematics(Q), jacobian=False)
    return float(np.max(np.abs(r)))


@pytest.mark.parametrize("name, preset", MODELS)
def test_predicted_start_solves_to_the_cold_configuration(name, preset):
    mech = pincal.load_mechanism(name)
    params = pincal.parameters(mech, preset)
    rows = pincal.sample_actuators(mech, 40, np.random.default_rng(3))
    v0 = 2e-4 * np.random.default_rng(4).standard_normal(len(params))
    m0 = params.apply(mech, v0)
    Q0, bk0 = m0.configurations_batch(rows)
    delta = 1e-4 * np.random.default_rng(5).standard_normal(len(params))
    m1 = params.apply(mech, v0 + delta)
    pred = predict_configurations(m0, params, bk0, v0, delta)
    assert pred is not None and pred.shape == Q0.shape
    # second order: the predicted start's closure residual falls as δ², the old one as δ
    m_small = params.apply(mech, v0 + 0.1 * delta)
    pred_small = predict_configurations(m0, params, bk0, v0, 0.1 * delta)
    old, old_small = _residual(m1, Q0), _residual(m_small, Q0)
    new, new_small = _residual(m1, pred), _residual(m_small, pred_small)
    assert 5 < old / old_small < 20, (old, old_small)
    assert new < 0.1 * old and new / new_small > 50, (new, new_small)
    Q_pred, bk = m1.configurations_batch(rows, pred)
    Q_cold, _ = m1.configurations_batch(rows)
    assert np.allclose(Q_pred, Q_cold, rtol=0, atol=1e-9)
    signs = np.sign(np.linalg.det(bk.closure_jacobian))
    assert np.all(signs == m1.home_branch)
    assert _residual(m1, Q_pred) <= m1.options.tol


@pytest.mark.parametrize("name, preset", MODELS[:2])
def test_point_closure_rates_equal_the_generic_twists(name, preset):
    mech = pincal.load_mechanism(name)
    params = pincal.parameters(mech, preset)
    rows = pincal.sample_actuators(mech, 16, np.random.default_rng(6))
    values = 1e-4 * np.random.default_rng(7).standard_normal(len(params))
    m = params.apply(mech, values)
    _, bk = m.configurations_batch(rows)
    delta = np.random.default_rng(8).standard_normal(len(params))
    plan = jacobian_plan(m, params)
    fast = _batch_predict._point_closure_rates(m, params, bk, values, plan, delta)
    place, P = param_twists(m, params, bk, values, plan, delta)
    generic = np.concatenate(
        [
            _batch_predict.closure_jacobian_batch(
                c, *place[c.frame_a], *place[c.frame_b], P[c.frame_a], P[c.frame_b]
            )[..., 0]
            for c in m.closures
        ],
        axis=1,
    )
    assert np.allclose(fast, generic, rtol=0, atol=1e-12 * np.max(np.abs(generic)))
    # and both equal the central difference of the closure residuals at fixed q
    eps = 1e-7

    def residuals(v):
        moved = params.apply(mech, v)
        return moved.closure_terms_batch(moved.batch_model.kinematics(bk.q), jacobian=False)[0]

    r_p, r_m = residuals(values + eps * delta), residuals(values - eps * delta)
    assert np.allclose(fast, (r_p - r_m) / (2 * eps), rtol=0, atol=1e-7)


def test_predicted_start_needs_one_newton_iteration(monkeypatch):
    mech = pincal.load_mechanism("stewart_6ups")
    params = pincal.parameters(mech, "stewart42")
    rows = pincal.sample_actuators(mech, 50, np.random.default_rng(9))
    Q0, bk0 = mech.configurations_batch(rows)
    delta = 1e-6 * np.random.default_rng(10).standard_normal(len(params))
    m1 = params.apply(mech, delta)
    pred = predict_configurations(mech, params, bk0, np.zeros(len(params)), delta)
    walks = {"n": 0}
    kin = type(m1.batch_model).kinematics

    def count(self, Q):
        walks["n"] += 1
        return kin(self, Q)

    monkeypatch.setattr(type(m1.batch_model), "kinematics", count)
    m1.configurations_batch(rows, Q0)
    from_old = walks["n"]
    walks["n"] = 0
    m1.configurations_batch(rows, pred)
    # one Newton step + the check, where the old solution needs two steps + the check
    assert walks["n"] == 2 and from_old == 3


def _measurements(n: int):
    mech = pincal.load_mechanism("stewart_6ups")
    params = pincal.parameters(mech, "stewart42")
    truth = np.random.default_rng(1).normal(0.0, 5e-4, len(params))
    rows = pincal.sample_actuators(mech, n, np.random.default_rng(n))
    meas = pincal.simulate_measurements(
        params.apply(mech, truth), rows, pincal.NoiseModel(0.01, 0.02), np.random.default_rng(2)
    )
    return mech, params, meas


def test_identify_result_unchanged_by_predicted_starts(monkeypatch):
    mech, params, meas = _measurements(150)
    with_prediction = pincal.identify(mech, params, meas)
    calls = {"n": 0}
    guesses = PoseConfigurations._guesses

    def counted(self, values):
        calls["n"] += 1 if self.predict_starts and self._solved is not None else 0
        return guesses(self, values)

    monkeypatch.setattr(PoseConfigurations, "_guesses", counted)
    pincal.identify(mech, params, meas)
    assert calls["n"] >= 2  # Gauss–Newton's solves started from predictions
    monkeypatch.setattr(_pose_configurations, "predict_configurations", lambda *a: None)
    plain = pincal.identify(mech, params, meas)
    a, b = np.asarray(with_prediction.values), np.asarray(plain.values)
    assert with_prediction.iterations == plain.iterations
    assert np.max(np.abs(a - b)) <= 1e-10 * np.max(np.abs(b))
    cov_a, cov_b = np.asarray(with_prediction.covariance), np.asarray(plain.covariance)
    assert np.max(np.abs(cov_a - cov_b)) <= 1e-8 * np.max(np.abs(cov_b))


def test_identify_solves_and_differentiates_once_per_accepted_point(monkeypatch):
    mech, params, meas = _measurements(120)
    calls = {"solve": 0, "sens": 0}
    solve, sens = Mechanism.configurations_batch, _problem.sensitivities_batch

    def count_solve(self, *a, **k):
        calls["solve"] += 1
        return solve(self, *a, **k)

    def count_sens(*a, **k):
        calls["sens"] += 1
        return sens(*a, **k)

    monkeypatch.setattr(Mechanism, "configurations_batch", count_solve)
    monkeypatch.setattr(_problem, "sensitivities_batch", count_sens)
    res = pincal.identify(mech, params, meas)
    # start + one per accepted step; the convergence test and the covariance reuse the
    # last evaluation (no extra solve or Jacobian)
    assert res.extras.rejected_steps == 0
    assert calls["solve"] == calls["sens"] == res.iterations
