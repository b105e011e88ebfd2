"""QPSO: known minima, the update rule, reproducibility, step-wise stage."""

from __future__ import annotations

import numpy as np
import pytest

from pincal.errors import ParameterError
from pincal.identification import (
    QPSOResult,
    qpso,
    qpso_stepwise,
)


def sphere(X: np.ndarray) -> np.ndarray:
    return np.sum(X**2, axis=1)


def rosenbrock(X: np.ndarray) -> np.ndarray:
    return np.sum(100.0 * (X[:, 1:] - X[:, :-1] ** 2) ** 2 + (1.0 - X[:, :-1]) ** 2, axis=1)


def test_sphere_10d_reaches_1e_8():
    d = 10
    res = qpso(sphere, -5 * np.ones(d), 5 * np.ones(d), rng=1, vectorized=True)
    assert isinstance(res, QPSOResult)
    assert res.fun < 1e-8
    assert np.max(np.abs(res.x)) < 1e-4
    assert res.fun == pytest.approx(float(np.sum(res.x**2)), abs=1e-300)
    assert res.iterations == 300
    assert res.nfev == 80 * 301
    assert res.history.shape == (301,)
    assert np.all(np.diff(res.history) <= 0.0)
    assert res.history[-1] == res.fun
    assert res.history[0] > 1.0  # it started far away


def test_rosenbrock_10d_with_fixed_seed():
    # QPSO is slow on the Rosenbrock valley: with 40 particles and 5000 iterations
    # seeds 0..9 end between 0.2 and 1.4 (from ~1e3 at initialisation).
    d = 10
    res = qpso(
        rosenbrock,
        -2 * np.ones(d),
        2 * np.ones(d),
        n_particles=40,
        t_max=5000,
        rng=0,
        vectorized=True,
    )
    assert res.fun < 2.0
    assert res.history[0] > 100.0
    assert np.all(np.diff(res.history) <= 0.0)
    assert res.fun == pytest.approx(rosenbrock(res.x[None, :])[0])


def test_same_seed_same_result_and_other_seed_differs():
    lo, hi = -np.ones(4), np.ones(4)
    a = qpso(sphere, lo, hi, n_particles=10, t_max=20, rng=7, vectorized=True)
    b = qpso(
        sphere, lo, hi, n_particles=10, t_max=20, rng=np.random.default_rng(7), vectorized=True
    )
    c = qpso(sphere, lo, hi, n_particles=10, t_max=20, rng=8, vectorized=True)
    np.testing.assert_array_equal(a.x, b.x)
    np.testing.assert_array_equal(a.history, b.history)
    assert not np.array_equal(a.x, c.x)


def test_scalar_and_vectorized_objectives_agree_and_stay_in_bounds():
    lo, hi = np.array([-1.0, 0.5, -3.0]), np.array([2.0, 0.7, -1.0])
    seen = []

    def scalar(x):
        assert x.shape == (3,)
        seen.append(x.copy())
        return float(np.sum((x - 0.1) ** 2))

    a = qpso(scalar, lo, hi, n_particles=6, t_max=15, rng=3)
    b = qpso(
        lambda X: np.sum((X - 0.1) ** 2, axis=1),
        lo,
        hi,
        n_particles=6,
        t_max=15,
        rng=3,
        vectorized=True,
    )
    np.testing.assert_allclose(a.x, b.x, rtol=0, atol=1e-15)
    assert a.nfev == len(seen) == 6 * 16
    pts = np.asarray(seen)
    assert np.all(pts >= lo) and np.all(pts <= hi)
    # the bound-constrained minimiser is the clipped unconstrained one
    c = qpso(
        lambda X: np.sum((X - 0.1) ** 2, axis=1),
        lo,
        hi,
        n_particles=20,
        t_max=200,
        rng=3,
        vectorized=True,
    )
    np.testing.assert_allclose(c.x, [0.1, 0.5, -1.0], atol=1e-6)


def test_one_iteration_matches_the_update_formula():
    """Recompute X(1) from the paper's equations (11)-(13) with the same random draws."""
    n, d = 5, 3
    lo, hi = -10 * np.ones(d), 10 * np.ones(d)
    evaluated = []

    def f(X):
        evaluated.append(X.copy())
        return np.sum((X - 1.0) ** 2, axis=1)

    qpso(f, lo, hi, n_particles=n, t_max=1, rng=11, vectorized=True, alpha=(0.8, 0.5))
    X0, X1 = evaluated
    ref = np.random.default_rng(11)
    np.testing.assert_array_equal(X0, lo + ref.random((n, d)) * (hi - lo))
    P, Pg = X0, X0[np.argmin(f(X0))]
    C = P.mean(axis=0)
    phi, u, s = ref.random((n, d)), 1.0 - ref.random((n, d)), ref.random((n, d))
    p = phi * P + (1 - phi) * Pg
    step = 0.8 * np.abs(C - X0) * np.log(1 / u)  # alpha at t = 0 is the start value
    expected = np.clip(np.where(s < 0.5, p - step, p + step), lo, hi)
    np.testing.assert_allclose(X1, expected, rtol=0, atol=1e-12)


def test_x0_callback_and_nonfinite_values():
    lo, hi = -np.ones(2), np.ones(2)
    x0 = np.array([0.25, -0.5])
    res = qpso(
        lambda X: np.sum((X - x0) ** 2, axis=1),
        lo,
        hi,
        n_particles=5,
        t_max=0,
        x0=x0,
        rng=0,
        vectorized=True,
    )
    np.testing.assert_array_equal(res.x, x0)
    assert res.fun == 0.0 and res.iterations == 0

    calls = []

    def stop_at_3(t, x, fx):
        calls.append(t)
        return t == 3

    res = qpso(sphere, lo, hi, n_particles=5, t_max=50, rng=0, vectorized=True, callback=stop_at_3)
    assert calls == [1, 2, 3] and res.iterations == 3 and res.stopped_by_callback

    # NaN counts as +inf: the minimiser avoids the NaN half-plane x0 < 0
    res = qpso(
        lambda X: np.where(X[:, 0] < 0, np.nan, np.sum(X**2, axis=1)),
        lo,
        hi,
        n_particles=10,
        t_max=100,
        rng=0,
        vectorized=True,
    )
    assert res.x[0] >= 0 and np.isfinite(res.fun)


@pytest.mark.parametrize(
    "lower, upper",
    [([0.0, 0.0], [1.0]), ([0.0, 1.0], [1.0, 1.0]), ([0.0], [np.inf]), ([], [])],
)
def test_bad_bounds_raise(lower, upper):
    with pytest.raises(ParameterError):
        qpso(sphere, lower, upper, vectorized=True)


def test_bad_objective_shape_and_x0_raise():
    with pytest.raises(ParameterError, match="shape"):
        qpso(lambda X: X, [0, 0], [1, 1], vectorized=True, t_max=1)
    with pytest.raises(ParameterError, match="x0"):
        qpso(sphere, [0, 0], [1, 1], vectorized=True, x0=[2.0, 0.0])


def test_stepwise_recovers_separable_quadratic_in_convergence_order():
    w = np.array([1.0, 100.0, 10.0, 1000.0, 0.1])
    c = np.array([0.3, -0.2, 0.01, 0.04, -0.45])
    lo, hi = -np.ones(5), np.ones(5)

    def f(X):
        return np.sum(w * (X - c) ** 2, axis=1)

    res = qpso_stepwise(f, lo, hi, n_particles=40, t_max=300, rng=0, vectorized=True)
    # each parameter is fixed once; the stiffest one converges (and is fixed) first
    assert sorted(res.order) == list(range(5))
    assert res.order == tuple(np.argsort(-w))
    assert all(s.converged for s in res.stages)
    # coarse values are within the convergence tolerance (1e-3 of the width 2)
    np.testing.assert_allclose(res.coarse_x, c, atol=5e-3)
    for s in res.stages:
        assert res.coarse_x[s.index] == s.value
    np.testing.assert_allclose(res.x, c, atol=1e-8)
    assert res.fun <= res.coarse_fun
    assert res.fun == pytest.approx(f(res.x[None])[0])
    assert res.nfev > res.fine.nfev

    again = qpso_stepwise(f, lo, hi, n_particles=40, t_max=300, rng=0, vectorized=True)
    np.testing.assert_array_equal(res.x, again.x)
    assert res.order == again.order


def test_stepwise_falls_back_when_nothing_converges():
    # t_max too short for the convergence test: each stage fixes the least-spread one
    res = qpso_stepwise(
        sphere, -np.ones(3), np.ones(3), n_particles=10, t_max=3, rng=0, vectorized=True, patience=5
    )
    assert sorted(res.order) == [0, 1, 2]
    assert not any(s.converged for s in res.stages)
