"""The one fit driver gives what the fit sequence it replaces gives, step by step.

Each route (a pose file, a joint fit of several data sets) is run through
:func:`identify` / :func:`identify_instruments` — the driver — and through the sequence
of its steps called directly here (evaluate at the start, decide the base set, hold the
weak directions, solve, settle, re-decide at the solution, finish). The two must agree
exactly: a driver that decides another set, solves another problem or settles another
way fails here. The typed joint details survive ``identification.json``.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from pincal.identification import (
    GaussNewtonOptions,
    IdentificationProblem,
    InstrumentProblem,
    LMOptions,
    identify,
    identify_instruments,
    result_from_dict,
    result_to_dict,
)
from pincal.identification.problem._gauge import null_motions, weak_parameters
from pincal.identification.results._result import ResidualStats
from pincal.identification.solvers._finish import finish, settle
from pincal.identification.solvers._noise import initial_weights, weighted_fit
from pincal.identification.solvers._solvers import solver
from pincal.measure import SocketPlate, simulate_measurements, simulate_sockets
from pincal.model import degenerate_translations, load_mechanism, parameters
from pincal.sensitivity import analyse_jacobian


def _pose_sequence(problem: IdentificationProblem, method: str, opts):
    """The pose route's steps by hand (these closures break nothing where batched)."""
    entry = solver(method)
    model, x0 = problem.model, problem.x0
    _, J0, raw0 = model.evaluate(x0)
    model, J0 = initial_weights(model, J0, raw0)
    names = problem.params.names
    split = np.isin(names, degenerate_translations(problem.mech))
    Js = model.structural_jacobian(x0)
    ident = analyse_jacobian(Js, names, splits_joint=split, units=problem.params.units)
    cand = problem.fit_indices
    sub = analyse_jacobian(Js[:, cand], tuple(names[i] for i in cand), splits_joint=split[cand])
    free = cand if sub.full_rank else cand[sub.base]
    out, model, weighting = weighted_fit(model, entry, x0, free, opts)
    s = settle(model, out, free)
    comps = tuple(problem.pose_file.components)
    prior = opts.prior_weights(x0.size)
    result, _ = finish(
        model, s, method=method, params=problem.params, raw0=raw0,
        stats=lambda raw: ResidualStats.from_residuals(raw, comps), residuals=s.raw,
        initial_values=x0, prior=prior, identifiability=ident,
        weighting=weighting, initial_residuals=raw0, components=comps,
    )  # fmt: skip
    return result


def _same(a, b) -> None:
    assert np.array_equal(a.identified, b.identified)
    assert np.array_equal(a.full_values, b.full_values)
    assert np.array_equal(a.covariance, b.covariance)
    assert a.reduced_chi2 == b.reduced_chi2 and a.cost_history == b.cost_history
    assert a.success == b.success and a.message.endswith(b.message)


@pytest.mark.parametrize(
    ("preset", "declared", "method", "opts"),
    [
        ("stewart42", True, "gauss-newton",
         GaussNewtonOptions(prior_std=(1e-3,) * 42, prior_mean=(0.0,) * 42)),
        ("stewart42", True, "lm", LMOptions(loss="huber")),
        # estimated noise; the base set leaves leg1_u1.rz out
        (["leg1_u1.tx", "leg1_u1.rz", "leg1_slide.offset"], False, "gauss-newton", None),
    ],
)  # fmt: skip
def test_the_pose_route_is_its_steps(stewart, stewart_poses, preset, declared, method, opts):
    params = parameters(stewart, preset)
    truth = np.random.default_rng(2).uniform(-3e-4, 3e-4, len(params))
    meas = simulate_measurements(params.apply(stewart, truth), stewart_poses[:16],
                                 {"position": 0.01, "orientation": 0.1},
                                 np.random.default_rng(5))  # fmt: skip
    if not declared:
        meas = dataclasses.replace(meas, noise=None)
    problem = IdentificationProblem(stewart, params, meas)
    driven = identify(problem, method=method, options=opts)
    by_hand = _pose_sequence(IdentificationProblem(stewart, params, meas), method,
                             solver(method).check_options(opts))  # fmt: skip
    _same(driven, by_hand)
    if not declared:  # the case exercises the reduction and the noise estimation
        assert driven.identified.sum() < len(params)
        assert driven.message.startswith(f"identified the {driven.identified.sum()} base")
        assert driven.weighting is not None and driven.weighting.source == "estimated"


@pytest.fixture(scope="module")
def ur5_sockets():
    mech = load_mechanism("ur5")
    params = parameters(mech, "full")
    bound = np.array([1e-3 if u == "m" else 1e-2 for u in params.units])
    actual = params.apply(mech, np.random.default_rng(2).uniform(-bound, bound))
    a = np.array([0.45, 0.10, 0.05])
    sockets = {"A": a, "B": a + np.array([0.05, 0.0, 0.0])}
    rng = np.random.default_rng(1)  # no known distance: the length scale is held (weak)
    return mech, params, [simulate_sockets(actual, SocketPlate("plate", 5e-6), sockets, 12, rng)]


def test_the_joint_route_is_its_steps(ur5_sockets):
    mech, params, datasets = ur5_sockets
    bound = (0.02, 0.1)
    fit = identify_instruments(mech, params, datasets, weak_bound=bound)
    model = InstrumentProblem(mech, params, datasets)
    entry, opts = solver("gauss-newton"), GaussNewtonOptions()
    x0, n, order = model.x0, model.n_machine, model.order
    _, J0, _ = model.evaluate(x0)
    ident = analyse_jacobian(J0[:, order], tuple(model.names[i] for i in order))
    free = np.sort(order[ident.base])
    weak = weak_parameters(J0, free, model.units, n, bound)
    free = np.setdiff1d(free, weak)
    P0, Jp0 = model.tool_points(x0)
    gauge = tuple(null_motions(J0, Jp0, P0, n, ident, order, model.names[n:]).lines())
    s = settle(model, entry.solve(model, x0, free, opts, None), free, noise_floor=True)
    f = s.fitted
    more = f[weak_parameters(s.Jf, np.arange(f.size), tuple(model.units[i] for i in f),
                             int(np.sum(f < n)), bound)]  # fmt: skip
    if more.size:
        weak, free = np.union1d(weak, more), np.setdiff1d(free, more)
        s = settle(model, entry.solve(model, x0, free, opts, None), free, noise_floor=True)
    assert weak.size  # the case holds something: the rule is exercised
    assert np.array_equal(fit.fitted, free) and fit.weak == tuple(model.names[i] for i in weak)
    assert np.array_equal(fit.values, s.out.x)
    assert fit.gauge[: len(gauge)] == gauge
    assert fit.result.reduced_chi2 == s.reduced_chi2
    assert fit.result.joint is not None and fit.result.joint.redundancy == s.dof
    assert fit.result.joint.gauge == fit.gauge
    # the typed details are what identification.json holds, and come back typed
    doc = result_to_dict(fit.result)
    assert doc["gauge"] == list(fit.gauge) and doc["redundancy"] == s.dof
    assert doc["instruments"] == fit.result.joint.instruments
    back = result_from_dict(doc)
    assert back.joint == fit.result.joint and "gauge" not in back.annotations
    assert result_to_dict(back) == doc


def test_the_marker_hold_loop_switches_holds_and_redecides_in_that_order():
    """drive_holding over a scripted fit: GN fails → LM; a 2σ beyond the bound → held;
    the set decided again at the solution is kept when it differs."""
    from types import SimpleNamespace

    from pincal.identification.solvers._driver import MarginalBound, drive_holding

    calls = []
    units = {"base.tx": "m", "a": "m", "b": "rad", "c": "m"}

    def fit(names, method, initial):
        calls.append((tuple(names), method, None if initial is None else tuple(initial)))
        std = {"base.tx": 1.0, "a": 0.011, "b": 0.01, "c": 1e-4}  # a: 2σ 22 mm > 20 mm
        mask = [n in names for n in units]
        if initial is not None:  # at the solution, one parameter fewer is identifiable
            mask[-1] = False
        return SimpleNamespace(
            success=method == "lm", message="stalled ", names=tuple(units),
            units=tuple(units.values()), identified=np.array(mask),
            std=np.array([std[n] for n, m in zip(units, mask, strict=True) if m]),
            full_values=np.arange(4.0),
        )  # fmt: skip

    out = drive_holding(fit, list(units), "gauss-newton", MarginalBound(0.02, 0.1),
                        lambda n: n.startswith("base."))  # fmt: skip
    every, kept = tuple(units), ("base.tx", "b", "c")
    assert calls == [(every, "gauss-newton", None), (every, "lm", None), (kept, "lm", None),
                     (kept, "lm", (0.0, 1.0, 2.0, 3.0))]  # fmt: skip
    assert out.method == "lm" and out.held == ("a",)
    assert out.notes[0].startswith("Gauss–Newton did not converge (stalled); switched")
    assert "held 1 machine parameters" in out.notes[1] and "a (2σ 22 mm)" in out.notes[1]
    assert "decided again at the solution has 2 parameters (at the start 3)" in out.notes[2]
    assert out.result.identified.sum() == 2


def test_the_hold_loop_skips_a_refit_whose_set_is_known_to_be_the_same():
    """drive_holding with a set count: the refit from the solution runs only when the
    count there differs from the fit's (a same-size refit is never kept)."""
    from types import SimpleNamespace

    from pincal.identification.solvers._driver import MarginalBound, drive_holding

    def run(count):
        calls = []

        def fit(names, method, initial):
            calls.append(initial is not None)
            mask = np.array([True, True, initial is None])
            return SimpleNamespace(
                success=True, message="", names=("a", "b", "c"), units=("m",) * 3,
                identified=mask, std=np.full(int(mask.sum()), 1e-4), full_values=np.zeros(3),
            )  # fmt: skip

        out = drive_holding(fit, ["a", "b", "c"], "gauss-newton", MarginalBound(0.02, 0.1),
                            lambda n: False, count)  # fmt: skip
        return calls, int(out.result.identified.sum())

    assert run(lambda names, x: 3) == ([False], 3)  # same count: no refit
    assert run(lambda names, x: 2) == ([False, True], 2)  # differs: refit, kept
    assert run(lambda names, x: None) == ([False, True], 2)  # unknown: refit
    assert run(None) == ([False, True], 2)


@pytest.mark.parametrize("declared", [False, True])
def test_the_count_known_at_the_start_is_what_the_fit_identifies(stewart, stewart_poses, declared):
    """fitted_at_start counts exactly the parameters identify fits, from nominal and from
    a solution (estimated noise; a declared noise re-checks at the solution: None)."""
    from pincal.identification._identify import fitted_at_start

    params = parameters(stewart, ["leg1_u1.tx", "leg1_u1.rz", "leg1_slide.offset"])
    truth = np.random.default_rng(3).uniform(-3e-4, 3e-4, len(params))
    meas = simulate_measurements(params.apply(stewart, truth), stewart_poses[:16],
                                 {"position": 0.01, "orientation": 0.1},
                                 np.random.default_rng(4))  # fmt: skip
    if not declared:
        meas = dataclasses.replace(meas, noise=None)
    first = IdentificationProblem(stewart, params, meas)
    result = identify(first)
    again = IdentificationProblem(stewart, params, meas, result.full_values)
    if declared:
        assert fitted_at_start(first) is None and fitted_at_start(again) is None
        return
    assert result.identified.sum() == 2  # the base set leaves leg1_u1.rz out
    assert fitted_at_start(first) == 2
    # at the solution the structural Jacobian sees leg1_u1.rz: the count says so
    assert fitted_at_start(again) == identify(again).identified.sum() == 3
