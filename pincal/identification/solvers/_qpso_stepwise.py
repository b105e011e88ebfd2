"""Seed 003's step-wise QPSO (section 2.2) on the swarm of :mod:`._qpso`.

A coarse stage fixes one parameter at a time in the order in which the parameters
converge, then a fine stage runs over all parameters started from the coarse result.
See :func:`qpso_stepwise` for how the paper's (unspecified) convergence test is read.
The function is generic: the objective is any callable of a parameter vector.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from pincal.errors import ParameterError
from pincal.identification.solvers._qpso import (
    Objective,
    QPSOResult,
    Swarm,
    alpha_at,
    alpha_pair,
    check_counts,
    initial_positions,
    qpso,
    search_bounds,
    swarm_evaluator,
)

__all__ = ["QPSOStage", "QPSOStepwiseResult", "qpso_stepwise"]

_log = logging.getLogger(__name__)


@dataclass(frozen=True)
class QPSOStage:
    """One coarse stage of :func:`qpso_stepwise`.

    Attributes:
        index: the parameter (index into the full vector) fixed by this stage.
        value: the value it was fixed at.
        iterations: swarm iterations the stage ran.
        converged: True if the convergence test fired; False if the stage hit
            t_max and the least-spread parameter was fixed instead.
        fun: best objective value of the stage.
    """

    index: int
    value: float
    iterations: int
    converged: bool
    fun: float


@dataclass(frozen=True)
class QPSOStepwiseResult:
    """Outcome of :func:`qpso_stepwise`.

    Attributes:
        x: final position (fine stage), shape (d,).
        fun: objective value at ``x``.
        order: parameter indices in the order the coarse stage fixed them.
        coarse_x: coarse-stage result, shape (d,).
        coarse_fun: objective value at ``coarse_x``.
        stages: the coarse stages, in order.
        fine: the fine-stage run over all parameters.
        nfev: objective evaluations over both stages.
    """

    x: np.ndarray
    fun: float
    order: tuple[int, ...]
    coarse_x: np.ndarray
    coarse_fun: float
    stages: tuple[QPSOStage, ...]
    fine: QPSOResult
    nfev: int


def qpso_stepwise(
    fun: Objective,
    lower: ArrayLike,
    upper: ArrayLike,
    n_particles: int = 80,
    t_max: int = 300,
    rng: np.random.Generator | int | None = None,
    alpha: tuple[float, float] = (1.0, 0.5),
    *,
    vectorized: bool = False,
    spread_tol: float = 1e-3,
    patience: int = 10,
    fine_t_max: int | None = None,
    fine_spread: float = 0.1,
) -> QPSOStepwiseResult:
    """Seed 003's step-wise QPSO: fix parameters one at a time, then refine all.

    Reading of the paper (section 2.2.1, steps 3–8, and 2.2.2):

    * Coarse stage. A swarm of N particles is initialised uniformly over the
      m still-free parameters (the fixed ones are held at their values inside
      the objective). After every iteration each free parameter j of the global
      best ``P_g`` is tested for convergence; the first to converge is fixed at
      ``P_g[j]``, m ← m − 1 and a fresh random swarm is started over the rest,
      until m = 0. The paper does not state the test; here parameter j has
      converged when the spread of the personal bests in that dimension,
      ``max_i P_ij − min_i P_ij``, is at most ``spread_tol·(upper_j − lower_j)``
      and ``P_g[j]`` moved by no more than that amount over the last
      ``patience`` iterations. If several converge in the same iteration the
      one with the smallest relative spread is fixed. If none converges within
      ``t_max`` iterations the least-spread parameter is fixed (logged).
    * Fine stage. The coarse result is the initial global best of a swarm over
      all d parameters (particle 0 at the coarse result, the others uniform
      within ``fine_spread·(upper − lower)/2`` of it), run for ``fine_t_max``
      iterations (default ``t_max``).

    Args:
        fun: objective of a full position, as for :func:`qpso`: with
            ``vectorized=False`` it maps a position (d,) to a scalar; with
            ``vectorized=True`` it maps positions (N, d) to values (N,). Non-finite
            values count as +inf.
        lower: lower box bounds, shape (d,), in the units of ``x``.
        upper: upper box bounds, shape (d,), in the units of ``x``; ``upper > lower``.
        n_particles: swarm size N of every stage (seed 003: 80).
        t_max: maximum number of iterations of each coarse stage (seed 003: 300).
        rng: a numpy Generator or a seed; the same seed gives the same result.
        alpha: contraction–expansion coefficient at the first and last iteration
            of a stage, varied linearly (seed 003: 1.0 → 0.5); a scalar is constant.
        vectorized: whether ``fun`` evaluates a whole swarm (N, d) in one call.
        spread_tol: relative spread of the convergence test (see above).
        patience: iterations over which ``P_g[j]`` must be stable.
        fine_t_max: iterations of the fine stage (default ``t_max``).
        fine_spread: relative initial spread of the fine-stage swarm.

    Returns:
        QPSOStepwiseResult with the fixing order, coarse and fine results.

    Raises:
        ParameterError: malformed bounds, tolerances or objective output.
    """
    lo, hi = search_bounds(lower, upper)
    check_counts(n_particles, t_max)
    a0, a1 = alpha_pair(alpha)
    if not spread_tol > 0 or int(patience) < 1 or not fine_spread > 0:
        raise ParameterError("spread_tol and fine_spread must be positive and patience ≥ 1")
    gen = np.random.default_rng(rng)
    d = lo.size
    evaluate_full = swarm_evaluator(fun, vectorized, d)
    x_fixed = 0.5 * (lo + hi)  # values of free entries are overwritten before every call
    free = list(range(d))
    stages: list[QPSOStage] = []
    nfev = 0
    width = hi - lo

    while free:
        idx = np.asarray(free)

        def evaluate(Z: np.ndarray, idx: np.ndarray = idx) -> np.ndarray:
            X = np.tile(x_fixed, (Z.shape[0], 1))
            X[:, idx] = Z
            return evaluate_full(X)

        swarm = Swarm(
            evaluate,
            initial_positions(gen, int(n_particles), lo[idx], hi[idx], None, 1.0),
            lo[idx],
            hi[idx],
            gen,
        )
        recent = [swarm.best_x]
        tol = spread_tol * width[idx]
        chosen, converged, t = -1, False, 0
        while t < t_max:
            swarm.step(alpha_at(t, t_max, a0, a1))
            t += 1
            recent.append(swarm.best_x)
            if len(recent) > patience + 1:
                recent.pop(0)
            rel_spread = np.ptp(swarm.P, axis=0) / width[idx]
            if len(recent) == patience + 1:
                drift = np.ptp(np.asarray(recent), axis=0)
                ok = (rel_spread * width[idx] <= tol) & (drift <= tol)
                if np.any(ok):
                    chosen = int(np.flatnonzero(ok)[np.argmin(rel_spread[ok])])
                    converged = True
                    break
        if chosen < 0:
            chosen = int(np.argmin(np.ptp(swarm.P, axis=0) / width[idx]))
            _log.info(
                "qpso_stepwise: no parameter converged in %d iterations; fixing %d",
                t_max,
                int(idx[chosen]),
            )
        nfev += swarm.nfev
        j = int(idx[chosen])
        best = swarm.best_x
        x_fixed[idx] = best  # the other free entries keep the stage's best as a warm value
        stages.append(QPSOStage(j, float(best[chosen]), t, converged, swarm.best_f))
        free.remove(j)

    coarse_x = x_fixed.copy()
    coarse_fun = float(evaluate_full(coarse_x[None, :])[0])
    nfev += 1
    fine = qpso(
        fun,
        lo,
        hi,
        n_particles,
        t_max if fine_t_max is None else fine_t_max,
        gen,
        (a0, a1),
        x0=coarse_x,
        vectorized=vectorized,
        init_spread=fine_spread,
    )
    nfev += fine.nfev
    x, f = (fine.x, fine.fun) if fine.fun <= coarse_fun else (coarse_x, coarse_fun)
    return QPSOStepwiseResult(
        x=x.copy(),
        fun=f,
        order=tuple(s.index for s in stages),
        coarse_x=coarse_x,
        coarse_fun=coarse_fun,
        stages=tuple(stages),
        fine=fine,
        nfev=nfev,
    )
