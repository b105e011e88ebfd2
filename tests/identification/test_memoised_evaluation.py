"""Identification evaluations are memoised per parameter vector and reuse kinematics."""

from __future__ import annotations

import numpy as np
import pytest

import pincal
from pincal.identification.problem import _problem
from pincal.identification.problem._problem import CalibrationProblem
from pincal.model import Mechanism


@pytest.fixture(scope="module")
def setup():
    mech = pincal.load_mechanism("stewart_6ups")
    params = pincal.parameters(mech, "stewart42")
    rows = pincal.sample_actuators(mech, 12, np.random.default_rng(0))
    truth = 1e-4 * np.random.default_rng(1).standard_normal(len(params))
    meas = pincal.simulate_measurements(params.apply(mech, truth), rows)
    return mech, params, meas


def test_repeated_evaluation_is_computed_once(setup, monkeypatch):
    mech, params, meas = setup
    problem = CalibrationProblem(mech, params, meas)
    calls = {"fk": 0, "jac": 0}
    fk, jac = Mechanism.configurations_batch, _problem.sensitivities_batch

    def count_fk(self, *a, **k):
        calls["fk"] += 1
        return fk(self, *a, **k)

    def count_jac(*a, **k):
        calls["jac"] += 1
        return jac(*a, **k)

    monkeypatch.setattr(Mechanism, "configurations_batch", count_fk)
    monkeypatch.setattr(_problem, "sensitivities_batch", count_jac)
    x = 1e-5 * np.ones(len(params))
    cost = problem.cost(x)  # residual only
    r1, J1, raw1 = problem.evaluate(x)  # Jacobian: reuses the closed configurations
    r2, J2, raw2 = problem.evaluate(x.copy())
    assert calls == {"fk": 1, "jac": 1}
    assert cost == pytest.approx(0.5 * float(r1 @ r1), rel=1e-14)
    assert r1 is r2 and J1 is J2 and raw1 is raw2
    assert not J1.flags.writeable  # shared results cannot be changed by a caller
    problem.evaluate(np.zeros(len(params)))
    assert calls == {"fk": 2, "jac": 2}


def test_memoised_values_equal_a_fresh_problem(setup):
    mech, params, meas = setup
    x = 2e-5 * np.arange(len(params)) / len(params)
    a = CalibrationProblem(mech, params, meas)
    a.cost(x)
    ra, Ja, _ = a.evaluate(x)
    rb, Jb, _ = CalibrationProblem(mech, params, meas).evaluate(x)
    np.testing.assert_allclose(ra, rb, rtol=0, atol=1e-9)
    np.testing.assert_allclose(Ja, Jb, rtol=0, atol=1e-9 * np.abs(Jb).max())


def test_identify_solves_each_trial_once_and_reuses_the_start(setup, monkeypatch):
    """No second pass at the start values for closure breaking (square closures break none)."""
    mech, params, meas = setup
    calls = {"fk": 0}
    fk = Mechanism.configurations_batch

    def count_fk(self, *a, **k):
        calls["fk"] += 1
        return fk(self, *a, **k)

    monkeypatch.setattr(Mechanism, "configurations_batch", count_fk)
    res = pincal.identify(mech, params, meas, noise={"position": 0.01, "orientation": 0.02})
    # one solve at the start, one per cost evaluation of the Gauss–Newton trials
    assert calls["fk"] == res.extras.evaluations - res.iterations + 1
    assert res.success
