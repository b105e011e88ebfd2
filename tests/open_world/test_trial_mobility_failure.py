"""Cause 5 of issue 28: a trial step whose mechanism cannot be built is a rejected step.

On the RSSR with an emulated ball joint (machines.rssr_emulated_ball) a random ``full``
perturbation moves the three revolutes apart: the coupler spin is no longer idle and
the mechanism is refused with a MobilityError. Every solver's trial evaluation must
read that as an unusable step (cost +inf), never raise it.
"""

from __future__ import annotations

import numpy as np
import pytest

from pincal.errors import MobilityError
from pincal.identification import identify
from pincal.identification._options import GaussNewtonOptions
from pincal.identification.problem._problem import CalibrationProblem
from pincal.identification.solvers._local import gauss_newton
from pincal.measure import simulate_measurements
from pincal.model import Mechanism, sample_actuators
from pincal.sensitivity import parameters
from tests.open_world.machines import rssr_emulated_ball


@pytest.fixture(scope="module")
def setup():
    mech = Mechanism(*rssr_emulated_ball())
    full = parameters(mech, "full")
    rows = sample_actuators(mech, 20, np.random.default_rng(11))
    base = parameters(mech, "base")
    truth = np.random.default_rng(1).normal(0, 2e-4, len(base))
    meas = simulate_measurements(base.apply(mech, truth), rows)
    bad = np.random.default_rng(0).normal(0, 1e-3, len(full))
    return mech, full, meas, bad


def test_the_perturbation_really_breaks_the_mechanism(setup):
    mech, full, _, bad = setup
    with pytest.raises(MobilityError, match="ball_z"):
        full.apply(mech, bad)


def test_cost_of_an_unbuildable_trial_is_infinite(setup):
    mech, full, meas, bad = setup
    problem = CalibrationProblem(mech, full, meas, noise={"position": 0.01})
    assert np.isfinite(problem.cost(np.zeros(len(full))))
    assert problem.cost(bad) == float("inf")


def test_gauss_newton_rejects_the_step_and_goes_on(setup, monkeypatch):
    """The first trial of Gauss–Newton is replaced by the breaking vector: the step is
    rejected (damped), and the fit still converges."""
    mech, full, meas, bad = setup
    problem = CalibrationProblem(mech, full, meas, noise={"position": 0.01})
    real, calls = problem.cost, []

    def cost(x):
        calls.append(1)
        return real(bad if len(calls) == 1 else x)

    monkeypatch.setattr(problem, "cost", cost)
    free = np.array([full.index(n) for n in parameters(mech, "base").names])
    out = gauss_newton(problem, np.zeros(len(full)), free, GaussNewtonOptions())
    assert out.success, out.message
    assert out.extras.rejected_steps >= 1


def test_identify_with_the_full_preset_does_not_raise(setup):
    mech, full, meas, _ = setup
    res = identify(mech, full, meas, noise={"position": 0.01})
    assert res.success, res.message
