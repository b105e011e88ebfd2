"""Quantum-behaved particle swarm optimisation (QPSO) for bounded minimisation.

QPSO (Sun, Feng & Xu 2004) moves every particle by sampling around a local
attractor instead of integrating a velocity. With N particles in d dimensions,
personal bests ``P`` (N, d), global best ``P_g`` (d,) and the mean best
``C = mean_i P_i``, one iteration draws per particle and dimension
``φ, u ~ U(0, 1)`` and a random sign, and sets::

    p_i = φ·P_i + (1 − φ)·P_g                  (local attractor)
    X_i = p_i ± α(t)·|C − X_i|·ln(1/u)          (new position)

The contraction–expansion coefficient α(t) decreases linearly from ``alpha[0]``
(iteration 0) to ``alpha[1]`` (last iteration); seed 003 uses 1.0 → 0.5 with
N = 80 and t_max = 300. New positions are clipped to the box.

:func:`pincal.identification.qpso_stepwise` (module ``_qpso_stepwise``) is the
two-stage variant of seed 003 built on this swarm.

The functions are generic: the objective is any callable of a parameter vector.
Units are whatever the caller's parameters use.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from pincal.errors import ParameterError

__all__ = ["QPSOResult", "qpso"]

_log = logging.getLogger(__name__)

Objective = Callable[[np.ndarray], "float | np.ndarray"]
Callback = Callable[[int, np.ndarray, float], "bool | None"]


@dataclass(frozen=True)
class QPSOResult:
    """Outcome of one QPSO run.

    Attributes:
        x: best position found, shape (d,).
        fun: objective value at ``x``.
        history: best objective value after initialisation (entry 0) and after
            each iteration, shape (iterations + 1,); non-increasing.
        nfev: number of objective evaluations (one per particle and iteration).
        iterations: number of swarm updates performed (≤ t_max).
        stopped_by_callback: True if the callback ended the run early.
    """

    x: np.ndarray
    fun: float
    history: np.ndarray
    nfev: int
    iterations: int
    stopped_by_callback: bool = False


# --------------------------------------------------------------------------- helpers


def search_bounds(lower: ArrayLike, upper: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """The box (lower, upper) as float (n,) vectors, checked finite and ordered."""
    lo = np.atleast_1d(np.asarray(lower, dtype=float))
    hi = np.atleast_1d(np.asarray(upper, dtype=float))
    if lo.ndim != 1 or lo.shape != hi.shape:
        raise ParameterError(
            f"lower and upper must be vectors of equal length, got shapes {lo.shape} and {hi.shape}"
        )
    if lo.size == 0:
        raise ParameterError("lower and upper must have at least one element")
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
        raise ParameterError("bounds must be finite")
    if np.any(hi <= lo):
        bad = np.flatnonzero(hi <= lo).tolist()
        raise ParameterError(f"upper must exceed lower in every dimension; violated at {bad}")
    return lo, hi


def alpha_pair(alpha: float | tuple[float, float]) -> tuple[float, float]:
    """The contraction–expansion coefficient as (start, end) (a scalar stays constant)."""
    a = np.asarray(alpha, dtype=float).ravel()
    if a.size == 1:
        a = np.array([a[0], a[0]])
    if a.size != 2 or np.any(a <= 0) or not np.all(np.isfinite(a)):
        raise ParameterError(f"alpha must be a positive scalar or (start, end) pair, got {alpha!r}")
    return float(a[0]), float(a[1])


def swarm_evaluator(fun: Objective, vectorized: bool, d: int) -> Callable[[np.ndarray], np.ndarray]:
    """Wrap ``fun`` to map (N, d) positions to (N,) values; non-finite → +inf."""

    def evaluate(X: np.ndarray) -> np.ndarray:
        if vectorized:
            f = np.asarray(fun(X), dtype=float)
            if f.shape != (X.shape[0],):
                raise ParameterError(
                    f"vectorized objective must return shape ({X.shape[0]},) for input "
                    f"shape {X.shape}, got {f.shape}"
                )
        else:
            f = np.empty(X.shape[0])
            for i, x in enumerate(X):
                v = np.asarray(fun(x.copy()), dtype=float)
                if v.size != 1:
                    raise ParameterError(
                        f"objective must return a scalar for input shape ({d},), got {v.shape}"
                    )
                f[i] = v.item()
        return np.where(np.isfinite(f), f, np.inf)

    return evaluate


def initial_positions(
    rng: np.random.Generator,
    n: int,
    lo: np.ndarray,
    hi: np.ndarray,
    x0: np.ndarray | None,
    spread: float,
) -> np.ndarray:
    """Uniform positions in the box, or around x0 (x0 itself is particle 0)."""
    if x0 is None:
        return lo + rng.random((n, lo.size)) * (hi - lo)
    half = 0.5 * spread * (hi - lo)
    X = np.clip(x0 + (2.0 * rng.random((n, lo.size)) - 1.0) * half, lo, hi)
    X[0] = x0
    return X


class Swarm:
    """Mutable swarm state; one :meth:`step` is one QPSO iteration."""

    def __init__(
        self,
        evaluate: Callable[[np.ndarray], np.ndarray],
        X: np.ndarray,
        lo: np.ndarray,
        hi: np.ndarray,
        rng: np.random.Generator,
    ) -> None:
        self.evaluate = evaluate
        self.lo, self.hi, self.rng = lo, hi, rng
        self.X = X
        self.P = X.copy()
        self.fP = evaluate(X)
        self.nfev = X.shape[0]
        self.g = int(np.argmin(self.fP))

    @property
    def best_x(self) -> np.ndarray:
        """Position of the best particle so far."""
        return self.P[self.g].copy()

    @property
    def best_f(self) -> float:
        """Cost of the best particle so far."""
        return float(self.fP[self.g])

    def step(self, alpha: float) -> None:
        """Move every particle once (quantum-behaved update about its attractor), in the box."""
        n, d = self.X.shape
        rng = self.rng
        C = self.P.mean(axis=0)
        phi = rng.random((n, d))
        attractor = phi * self.P + (1.0 - phi) * self.P[self.g]
        u = 1.0 - rng.random((n, d))  # in (0, 1], so ln(1/u) is finite
        sign = np.where(rng.random((n, d)) < 0.5, -1.0, 1.0)
        X = attractor + sign * alpha * np.abs(C - self.X) * np.log(1.0 / u)
        self.X = np.clip(X, self.lo, self.hi)
        f = self.evaluate(self.X)
        self.nfev += n
        better = f < self.fP
        self.P[better] = self.X[better]
        self.fP[better] = f[better]
        self.g = int(np.argmin(self.fP))


def alpha_at(t: int, t_max: int, a0: float, a1: float) -> float:
    """Coefficient at iteration t, linear from a0 to a1 over t_max iterations."""
    return a0 + (a1 - a0) * t / max(t_max - 1, 1)


def check_counts(n_particles: int, t_max: int) -> None:
    """ParameterError unless at least 2 particles and t_max ≥ 0."""
    if int(n_particles) < 2:
        raise ParameterError(f"n_particles must be at least 2, got {n_particles}")
    if int(t_max) < 0:
        raise ParameterError(f"t_max must be non-negative, got {t_max}")


# --------------------------------------------------------------------------- public API


def qpso(
    fun: Objective,
    lower: ArrayLike,
    upper: ArrayLike,
    n_particles: int = 80,
    t_max: int = 300,
    rng: np.random.Generator | int | None = None,
    alpha: tuple[float, float] = (1.0, 0.5),
    x0: ArrayLike | None = None,
    callback: Callback | None = None,
    *,
    vectorized: bool = False,
    init_spread: float = 1.0,
) -> QPSOResult:
    """Minimise ``fun`` over the box ``lower ≤ x ≤ upper`` with QPSO.

    Args:
        fun: objective. With ``vectorized=False`` it maps a position (d,) to a
            scalar; with ``vectorized=True`` it maps positions (N, d) to values
            (N,). Non-finite values count as +inf.
        lower: lower box bounds, shape (d,), in the units of ``x``.
        upper: upper box bounds, shape (d,), in the units of ``x``; ``upper > lower``.
        n_particles: swarm size N (seed 003: 80).
        t_max: number of iterations (seed 003: 300).
        rng: a numpy Generator or a seed; the same seed gives the same result.
        alpha: contraction–expansion coefficient at the first and last
            iteration, varied linearly (seed 003: 1.0 → 0.5); a scalar is constant.
        x0: optional start, shape (d,), inside the box. It becomes particle 0 and
            the others are drawn uniformly within ``init_spread·(upper − lower)/2``
            of it (clipped to the box).
        callback: called after each iteration as ``callback(t, x_best, f_best)``
            with t = 1..t_max; returning True stops the run.
        vectorized: see ``fun``.
        init_spread: see ``x0``; ignored without x0.

    Returns:
        QPSOResult with the best position, its value and the best-value history.

    Raises:
        ParameterError: malformed bounds, x0, swarm size or objective output.
    """
    lo, hi = search_bounds(lower, upper)
    check_counts(n_particles, t_max)
    a0, a1 = alpha_pair(alpha)
    gen = np.random.default_rng(rng)
    start = _start_vector(x0, lo, hi)
    if not init_spread > 0:
        raise ParameterError(f"init_spread must be positive, got {init_spread}")
    evaluate = swarm_evaluator(fun, vectorized, lo.size)
    swarm = Swarm(
        evaluate,
        initial_positions(gen, int(n_particles), lo, hi, start, init_spread),
        lo,
        hi,
        gen,
    )
    history = [swarm.best_f]
    stopped = False
    t = 0
    while t < t_max:
        swarm.step(alpha_at(t, t_max, a0, a1))
        t += 1
        history.append(swarm.best_f)
        if callback is not None and callback(t, swarm.best_x, swarm.best_f):
            stopped = True
            break
    _log.debug("qpso: %d iterations, %d evaluations, best %.6g", t, swarm.nfev, swarm.best_f)
    return QPSOResult(
        x=swarm.best_x,
        fun=swarm.best_f,
        history=np.asarray(history),
        nfev=swarm.nfev,
        iterations=t,
        stopped_by_callback=stopped,
    )


def _start_vector(x0: ArrayLike | None, lo: np.ndarray, hi: np.ndarray) -> np.ndarray | None:
    if x0 is None:
        return None
    x = np.atleast_1d(np.asarray(x0, dtype=float))
    if x.shape != lo.shape:
        raise ParameterError(f"x0 must have shape {lo.shape}, got {x.shape}")
    if np.any(x < lo) or np.any(x > hi):
        raise ParameterError("x0 must lie inside the bounds")
    return x
