"""Robust losses in Gauss–Newton, and a Gaussian prior that stays Gaussian under them.

Gauss–Newton minimises the robust cost ``½ f² Σ ρ((r/f)²)`` (plus a Gaussian prior's
``½ Σ ((x − mean)/σ)²``) with the loss' second-order model, as scipy's trust region does
for ``lm``. Both are checked against a general minimiser of that objective written out
here (BFGS), not against each other only. Before this, a robust loss ran scipy's ``trf``
alone and its loss applied to the prior's rows as well (a Huber prior: beyond 1.5σ of
the prior the parameter was pulled back linearly, not quadratically).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import minimize

from pincal.identification._options import GaussNewtonOptions, LMOptions
from pincal.identification._weighting import ROBUST_F_SCALE, loss_terms, robust_cost
from pincal.identification.solvers._levenberg_marquardt import levenberg_marquardt
from pincal.identification.solvers._local import gauss_newton

T = np.linspace(0.0, 2.0, 40)


class _Decay:
    """Whitened residuals of y = a·exp(−b·t) + c on 40 samples, 4 of them outliers."""

    solver_floor_cost = 0.0
    predict_starts = False
    n_equations = T.size

    def __init__(self, seed: int) -> None:
        rng = np.random.default_rng(seed)
        self.y = 2.0 * np.exp(-1.3 * T) + 0.5 + rng.normal(0.0, 1.0, T.size) * 0.05
        self.y[rng.choice(T.size, 4, replace=False)] += rng.choice([-1, 1], 4) * 0.6
        self.sigma = 0.05

    def evaluate(self, x: np.ndarray, jacobian: bool = True):
        a, b, c = x
        e = np.exp(-b * T)
        r = (self.y - (a * e + c)) / self.sigma
        J = None
        if jacobian:
            J = -np.column_stack([e, -a * T * e, np.ones_like(T)]) / self.sigma
        return r, J, r

    def cost(self, x: np.ndarray) -> float:
        r = self.evaluate(x, jacobian=False)[0]
        return 0.5 * float(r @ r)


def _objective(toy: _Decay, loss: str, std: np.ndarray | None, mean: np.ndarray):
    f = ROBUST_F_SCALE[loss]

    def value_and_gradient(x: np.ndarray) -> tuple[float, np.ndarray]:
        r, J, _ = toy.evaluate(x)
        _, slope, _ = loss_terms(loss, (r / f) ** 2)
        value, grad = robust_cost(loss, r, f), J.T @ (slope * r)
        if std is not None:
            value += 0.5 * float(np.sum(((x - mean) / std) ** 2))
            grad = grad + (x - mean) / std**2
        return value, grad

    return value_and_gradient


@pytest.mark.parametrize("loss", ["huber", "soft_l1", "cauchy"])
@pytest.mark.parametrize("prior", [False, True])
def test_both_solvers_reach_the_robust_minimum(loss, prior):
    toy, x0 = _Decay(seed=3), np.array([1.5, 1.0, 0.3])
    # a prior tight enough that the minimum sits beyond 1.5σ of it in a and c
    std = np.array([0.05, 0.5, 0.05]) if prior else None
    mean = np.array([1.8, 1.3, 0.6])
    kw = {"prior_std": tuple(std), "prior_mean": tuple(mean)} if prior else {}
    fun = _objective(toy, loss, std, mean)
    ref = minimize(fun, x0, jac=True, method="BFGS", options={"gtol": 1e-10})
    free = np.arange(3)
    gn = gauss_newton(toy, x0, free, GaussNewtonOptions(loss=loss, fallback=False, **kw))
    lm = levenberg_marquardt(toy, x0, free, LMOptions(loss=loss, **kw))
    for out in (gn, lm):
        assert out.success, out.message
        assert fun(out.x)[0] <= ref.fun * (1 + 1e-9), (out.x, ref.x)
        # (the parameters' σ here are ~1e-2: 1e-5 is 1e-3 σ, BFGS's own precision)
        np.testing.assert_allclose(out.x, ref.x, rtol=0, atol=1e-5)
    if prior:  # the prior binds beyond the loss' margin: a Huber prior would end elsewhere
        assert np.max(np.abs((ref.x - mean) / std)) > ROBUST_F_SCALE["huber"]


def test_gauss_newton_history_is_its_robust_cost():
    toy, x0 = _Decay(seed=5), np.array([1.5, 1.0, 0.3])
    out = gauss_newton(toy, x0, np.arange(3), GaussNewtonOptions(loss="huber", fallback=False))
    assert out.success, out.message
    assert out.history[-1] == pytest.approx(_objective(toy, "huber", None, x0)(out.x)[0])
    assert np.all(np.diff(out.history) <= 0.0)


def test_loss_terms_are_the_derivatives_of_rho():
    z = np.array([0.2, 0.9, 1.7, 6.0])
    h = 1e-6
    for loss in ("huber", "soft_l1", "cauchy", "arctan"):
        _, d1, d2 = loss_terms(loss, z)
        up, down = loss_terms(loss, z + h), loss_terms(loss, z - h)
        np.testing.assert_allclose(d1, (up[0] - down[0]) / (2 * h), atol=1e-8)
        np.testing.assert_allclose(d2, (up[1] - down[1]) / (2 * h), atol=1e-8)


def test_a_curved_valley_is_followed_under_a_robust_loss():
    """The re-weighted step is bent along the valley when straight steps fail.

    Without it Gauss–Newton with a Huber loss crawled along curved valleys (this one from
    (3, −1): 32 iterations; an MJCF Delta with ball-ended rods: 50, then
    Levenberg–Marquardt from the start; now 2 here, 23 there with the values of ``lm`` to
    4e-5 σ).
    """
    from tests.open_world.test_curved_valley import _Valley

    valley = _Valley()
    valley.solver_floor_cost, valley.predict_starts, valley.n_equations = 0.0, False, 2  # type: ignore[attr-defined]
    opts = GaussNewtonOptions(loss="huber", fallback=False, max_iterations=10)
    out = gauss_newton(valley, np.array([3.0, -1.0]), np.arange(2), opts)
    assert out.success, out.message
    np.testing.assert_allclose(out.x, [0.0, 0.0], atol=1e-10)
