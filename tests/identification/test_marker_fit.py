"""The Gaussian prior of the local solvers and the guards of fit_markers.

The prior is checked against the closed-form maximum a posteriori solution of the
linearised problem; the guards on a UR5 whose wrist barely moves (a real campaign's
"±0.02 rad" joint): its parameters are structurally identifiable but not numerically,
and must be held and named rather than returned with absurd values.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from pincal.errors import SolverOptionError
from pincal.identification import (
    GaussNewtonOptions,
    LMOptions,
    Prior,
    fit_markers,
    identify,
    is_registration,
)
from pincal.measure import MarkerSetup, Measurements, marker_mechanism
from pincal.model import BASE_JOINT, TOOL_JOINT, parameters, sample_actuators, with_joint_origin


def _ur5_case(n: int, wrist_span: float | None, seed: int):
    setup = MarkerSetup("wrist_3_link")
    mech = marker_mechanism("ur5", setup)
    actual = with_joint_origin(mech, BASE_JOINT, pin.SE3(pin.rpy.rpyToMatrix(0.2, 0.1, -0.5),
                                                         np.array([0.8, 0.5, -0.2])))  # fmt: skip
    actual = with_joint_origin(actual, TOOL_JOINT, pin.SE3(np.eye(3), np.array([0.02, 0.04, 0.1])))
    params = parameters(actual, "chain")
    rng = np.random.default_rng(seed)
    x = rng.uniform(-1e-3, 1e-3, len(params))
    x[[is_registration(n) for n in params.names]] = 0.0
    actual = params.apply(actual, x)
    q = sample_actuators(mech, n, rng)
    if wrist_span is not None:  # wrists 2 and 3 barely move
        q[:, 4:] = rng.uniform(-wrist_span, wrist_span, (n, 2))
    P = np.array([actual.frame_placement(c).translation for c in actual.configurations(q)])
    P += rng.normal(0, 5e-5, P.shape)
    meas = Measurements(q, P, None, ("x", "y", "z"), mech.measured_frame, mech.actuated)
    return mech, setup, meas


def test_prior_is_the_map_solution_of_the_linear_problem():
    """Gauss–Newton and LM with a prior land on (JᵀJ + W²)⁻¹Jᵀ(…) of the linearised fit."""
    mech, _, meas = _ur5_case(30, None, 1)
    from pincal.measure import register_markers

    start = register_markers(mech, meas).mechanism
    params = parameters(start, "chain")
    noise = {"position": 0.05, "orientation": 1.0}  # declared: fixed whitening
    free = identify(start, params, meas, "gauss-newton", noise=noise)
    names = list(free.identified_names)
    idx = np.flatnonzero(free.identified)
    std = np.full(len(params), 2e-4)  # a tight prior: the fit is pulled visibly
    prior = {"prior_std": tuple(std), "prior_mean": (0.0,) * len(std)}
    gn = identify(start, params, meas, "gauss-newton", noise=noise, fit=names,
                  options=GaussNewtonOptions(**prior))  # fmt: skip
    lm = identify(start, params, meas, "lm", noise=noise, fit=names, options=LMOptions(**prior))
    assert np.allclose(gn.full_values, lm.full_values, atol=1e-7)
    # MAP of the problem linearised at the prior-free optimum, solved in closed form
    from pincal.identification import IdentificationProblem

    problem = IdentificationProblem(start, params, meas, None, names, True, noise).model
    _, J, _ = problem.evaluate(free.full_values)
    J = J[:, idx]
    W2 = np.diag(1 / std[idx] ** 2)
    x_map = np.linalg.solve(J.T @ J + W2, J.T @ J @ free.full_values[idx])
    pull = np.max(np.abs(gn.full_values - free.full_values))
    assert pull > 1e-4  # the prior pulls by millimetres / mrad
    # equal up to the model's curvature over that pull (1 %; a sign or weight error is 100 %)
    assert np.max(np.abs(gn.full_values[idx] - x_map)) < 1e-2 * pull
    cov = np.linalg.inv(J.T @ J + W2)
    assert np.allclose(gn.std, np.sqrt(np.diag(cov)), rtol=0.05)
    with pytest.raises(SolverOptionError, match="together"):
        GaussNewtonOptions(prior_std=(1.0,))


@pytest.mark.slow  # ~80 s on a loaded 2-core box; the fast lane keeps the other marker fits
def test_weak_wrist_parameters_are_held_and_named():
    mech, setup, meas = _ur5_case(40, 0.02, 2)
    fit = fit_markers(mech, setup, meas)
    assert fit.result.success
    text = " ".join(fit.notes)
    assert "held" in text and "wrist" in text and "barely move" in text
    # whatever was fitted has a plausible uncertainty
    units = np.asarray(fit.result.units)[fit.result.identified]
    names = np.asarray(fit.result.names)[fit.result.identified]
    machine = np.array([not is_registration(n) for n in names])
    bound = np.where(units == "m", 0.02, 0.1)
    assert np.all(2 * fit.result.std[machine] <= bound[machine])


def test_prior_keeps_weak_parameters_near_nominal():
    mech, setup, meas = _ur5_case(40, 0.02, 3)
    fit = fit_markers(mech, setup, meas, prior=Prior(1e-3, 1e-3))
    vals = fit.result.full_values
    machine = [not is_registration(n) for n in fit.result.names]
    assert np.max(np.abs(vals[machine])) < 0.02  # no 0.25 m / 1.4 rad excursions


def test_gauss_newton_falls_back_to_lm_and_says_so():
    mech, setup, meas = _ur5_case(30, None, 4)
    fit = fit_markers(mech, setup, meas, max_iterations=1)  # GN cannot finish in one step
    assert fit.method == "lm"
    assert any("switched to Levenberg–Marquardt" in n for n in fit.notes)
    assert fit_markers(mech, setup, meas).method == "gauss-newton"


def test_a_robust_fit_with_a_prior_is_judged_by_its_whole_objective(caplog):
    """Huber + prior on the real TIAGo data: the prior's pull is not "ended worse".

    The check that a robust fit improved on its start scores robust cost + prior
    penalty, and does not ask the median residual to fall (the prior pulls by design).
    Fold 4 of the example's seed-0 split used to be called "not a solution".
    """
    import logging
    from pathlib import Path

    from pincal.io import read_marker_sets
    from pincal.validation import kfold

    data = Path(__file__).resolve().parents[2] / "docs/examples/tiago-mocap/measurements.csv"
    setup = MarkerSetup("arm_7_link", columns=("x1", "y1", "z1"))
    mech = marker_mechanism("tiago", setup)
    meas = read_marker_sets(data, mech, setup)[0]
    test = kfold(len(meas), 5, 0)[4]
    train = np.setdiff1d(np.arange(len(meas)), test)
    with caplog.at_level(logging.WARNING, logger="pincal.identification"):
        fit = fit_markers(mech, setup, meas.subset(train), prior=Prior(1e-2, 1e-2), loss="huber")
    assert fit.result.success, fit.result.message
    assert not [r for r in caplog.records if "ended worse" in r.getMessage()]


def test_a_robust_refit_from_its_own_solution_is_no_worse():
    """Re-started at its solution, a Huber fit ends where it began (to 1e-3 of the median)."""
    from pincal.identification.problem._problem import CalibrationProblem
    from pincal.identification.results._outcome import SolverOutcome
    from pincal.identification.solvers._noise import _robust_progress

    mech, setup, meas = _ur5_case(30, None, 2)
    fit = fit_markers(mech, setup, meas, loss="huber")
    start = fit.registration.mechanism
    params = parameters(start, "chain")
    model = CalibrationProblem(start, params, meas)
    x = fit.result.full_values
    jitter = x + 1e-9  # the solver's last-digit wander around its own solution
    out = SolverOutcome(jitter, 3, (1.0,), True, "converged (xtol)")
    _, _, raw_j = model.evaluate(jitter)
    kept = _robust_progress(model, x, jitter, raw_j / model.sigma, "huber", 1.345, out)
    assert kept.success, kept.message
