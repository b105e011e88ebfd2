"""Forward kinematics of an actuator draw with no assembly fails fast (bounded work).

The 3-PRS (tests/model/machines/prs3) with the slides at opposite ends of their range
does not close. The direct solve from home fails, then the continuation from home
walks to the edge of the workspace and halves its step down to the smallest one; each
of those corrector solves now has a short budget instead of the full Newton budget
(measured: ~1 200 residual evaluations in all, 5 600–9 500 before).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import pincal.model.loops._assembly as assembly
from pincal.errors import ConvergenceError
from pincal.model import SolverOptions, load_mechanism
from pincal.model.loops._branch import corrector_options
from pincal.model.loops._newton import damped_newton
from tests.open_world.machines import MODEL_MACHINES


@pytest.fixture
def evaluations(monkeypatch):
    """Count every closure-residual evaluation of the mechanisms' Newton solves."""
    count = [0]
    solve = assembly.damped_newton

    def counting(model, q0, free, evaluate, jacobian, options):
        def counted(q):
            count[0] += 1
            return evaluate(q)

        return solve(model, q0, free, counted, jacobian, options)

    monkeypatch.setattr(assembly, "damped_newton", counting)
    return count


@pytest.mark.parametrize("q_act", [[0.1, 0.3, 0.1], [0.3, 0.1, 0.3], [0.12, 0.28, 0.2]])
def test_infeasible_draw_fails_within_a_bounded_number_of_evaluations(evaluations, q_act):
    mech = load_mechanism(MODEL_MACHINES / "prs3")
    with pytest.raises(ConvergenceError, match="home assembly branch"):
        mech.configuration(np.array(q_act))
    assert 0 < evaluations[0] <= 2000


def test_feasible_draw_is_unchanged_by_the_corrector_budget(evaluations):
    mech = load_mechanism(MODEL_MACHINES / "prs3")
    q_act = mech.actuators_of(mech.q_home) + np.array([0.02, -0.015, 0.01])
    q = mech.configuration(q_act)
    assert np.max(np.abs(mech.closure_residual(q))) <= mech.options.tol
    assert np.allclose(mech.actuators_of(q), q_act, atol=1e-15)


def test_corrector_options_keep_tolerances_and_cap_the_budget():
    base = SolverOptions()
    short = corrector_options(base)
    assert (short.tol, short.rcond, short.max_step) == (base.tol, base.rcond, base.max_step)
    assert short.max_iterations < base.max_iterations
    assert short.max_backtracks < base.max_backtracks
    tight = SolverOptions(max_iterations=3, max_backtracks=2)
    assert corrector_options(tight) == tight  # never more than the caller allows


def _no_root_problem():
    """x² + 1 = 0 on a one-dof prismatic joint: no root, Newton wanders forever."""
    model = pin.Model()
    model.addJoint(0, pin.JointModelPX(), pin.SE3.Identity(), "x")
    state = {}

    def evaluate(q):
        state["x"] = float(q[0])
        return np.array([q[0] ** 2 + 1.0])

    def jacobian():
        return np.array([[2.0 * state["x"]]])

    return model, evaluate, jacobian


@pytest.mark.parametrize("backtracks", [1, 4, 30])
def test_line_search_halvings_are_capped(backtracks):
    model, evaluate, jacobian = _no_root_problem()
    calls = [0]

    def counted(q):
        calls[0] += 1
        return evaluate(q)

    options = SolverOptions(max_iterations=10, max_backtracks=backtracks)
    with pytest.raises(ConvergenceError):
        damped_newton(model, np.array([0.3]), np.array([0]), counted, jacobian, options)
    assert calls[0] <= 1 + options.max_iterations * backtracks
