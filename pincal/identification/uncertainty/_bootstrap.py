"""Parametric bootstrap of a fit, on request: a second opinion beside the linear σ.

:func:`bootstrap_covariance` draws new data from the fitted model with the fit's noise,
``y* = f(x̂) + s·σ·ε``, and refits them from x̂. In whitened residuals that needs
nothing but the problem's own evaluation:

    r*(x) = (y* − f(x)) / σ = r(x) − r(x̂) + s·ε,   ε ~ N(0, I),

so any object with ``evaluate(x, jacobian=True) -> (r, J, ...)`` — a pose problem or a
scalar-instrument problem — can be bootstrapped. Each refit is a damped Gauss–Newton
(Levenberg–Marquardt) on the free parameters. The noise vectors are drawn in the caller
from ``seed`` (the same σ for any number of workers); with ``n_jobs`` ≠ 1 and a
picklable ``factory`` that rebuilds the problem (Pinocchio models do not pickle), the
refits run in joblib worker processes.

The bootstrap is *reported*, never written as the calibration's covariance: a sample
covariance of B refits in k dimensions has B − 1 degrees of freedom, and at the
condition numbers of a calibration (10³–10⁴) its inverse — what a Mahalanobis distance
or a joint region uses — is dominated by sampling noise. Its per-parameter σ (relative
standard error ≈ 1/√(2B)) are what it is good for.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from pincal.errors import PincalError
from pincal.identification.problem import ResidualModel
from pincal.identification.uncertainty._linearity import TRIAL_ERRORS

__all__ = ["Bootstrap", "bootstrap_covariance", "check_draws"]

_MAX_ITERATIONS = 100
_CONVERGED = 1e-8  # a step that would lower ‖r‖² by less than this: converged (whitened)


@dataclass(frozen=True)
class Bootstrap:
    """A parametric bootstrap of a fit.

    Attributes:
        covariance: (n_free, n_free) sample covariance of the refits about x̂ [SI]
            (reported for its diagonal; never inverted by pincal).
        draws: refits used; failed: refits that raised or did not converge (left out).
        seed: the seed of the noise draws.
    """

    covariance: np.ndarray
    draws: int
    failed: int
    seed: int

    @property
    def std(self) -> np.ndarray:
        """(n_free,) bootstrap standard deviations [SI]."""
        return np.sqrt(np.clip(np.diag(self.covariance), 0.0, None))


def check_draws(draws: int) -> int:
    """``draws`` when it is an integer ≥ 2 (a sample σ needs two refits).

    Raises:
        PincalError: anything else.
    """
    if isinstance(draws, bool) or not isinstance(draws, int | np.integer) or draws < 2:
        raise PincalError(f"a bootstrap needs an integer number of refits ≥ 2 (e.g. 100), "
                          f"got {draws!r}")  # fmt: skip
    return int(draws)


def _refit(problem: ResidualModel, x: np.ndarray, idx: np.ndarray, shift: np.ndarray
           ) -> np.ndarray | None:  # fmt: skip
    """Levenberg–Marquardt on ``r(x) + shift`` over the free parameters, from x."""
    x = x.copy()
    r, J, *_ = problem.evaluate(x, jacobian=True)
    r = np.asarray(r, dtype=float) + shift
    cost = float(r @ r)
    lam = 1e-3
    for _ in range(_MAX_ITERATIONS):
        Jf = np.asarray(J, dtype=float)[:, idx]
        d = np.sqrt(np.maximum(np.sum(Jf**2, axis=0), 1e-300))
        gn = np.linalg.lstsq(Jf, -r, rcond=None)[0]
        if float(np.sum((Jf @ gn) ** 2)) < _CONVERGED:  # the Gauss–Newton step gains nothing
            return x
        while True:
            A = np.vstack([Jf, np.diag(np.sqrt(lam) * d)])
            b = np.concatenate([-r, np.zeros(idx.size)])
            dx = np.linalg.lstsq(A, b, rcond=None)[0]
            xt = x.copy()
            xt[idx] += dx
            try:
                rt, Jt, *_ = problem.evaluate(xt, jacobian=True)
            except TRIAL_ERRORS:  # a trial vector the model cannot assemble or solve
                rt = None
            if rt is not None:
                rt = np.asarray(rt, dtype=float) + shift
                ct = float(rt @ rt)
                if np.isfinite(ct) and ct <= cost:
                    break
            lam *= 10.0
            if lam > 1e12:
                return None
        x, r, J, cost = xt, rt, Jt, ct
        lam = max(lam / 10.0, 1e-9)
    return None


def _refits(problem: ResidualModel, x: np.ndarray, idx: np.ndarray, shifts: np.ndarray
            ) -> list[np.ndarray | None]:  # fmt: skip
    """One refit per row of ``shifts``: the free parameters' change, None when it failed."""
    out: list[np.ndarray | None] = []
    for shift in shifts:
        try:
            xb = _refit(problem, x, idx, shift)
        except TRIAL_ERRORS:
            xb = None
        out.append(None if xb is None or not np.all(np.isfinite(xb)) else xb[idx] - x[idx])
    return out


def _worker(factory: Callable[[], ResidualModel], x: np.ndarray, idx: np.ndarray,
            r0: np.ndarray, shifts: np.ndarray) -> list[np.ndarray | None] | None:  # fmt: skip
    """A worker process: rebuild the problem once, refit its share of the draws.

    None when the rebuilt problem does not give the caller's residual ``r0`` at x (the
    caller then refits that share itself).
    """
    from threadpoolctl import threadpool_limits

    with threadpool_limits(1):
        try:
            problem = factory()
            r = np.asarray(problem.evaluate(x, jacobian=False)[0], dtype=float)
        except TRIAL_ERRORS:
            return None
        if r.shape != r0.shape or not np.allclose(r, r0, rtol=1e-8, atol=1e-8):
            return None
        return _refits(problem, x, idx, shifts)


def bootstrap_covariance(
    problem: ResidualModel,
    x: np.ndarray,
    free: np.ndarray | None = None,
    *,
    scale: float = 1.0,
    draws: int = 100,
    seed: int = 0,
    progress: Callable[[int, int], None] | None = None,
    n_jobs: int = 1,
    factory: Callable[[], ResidualModel] | None = None,
) -> Bootstrap:
    """Covariance of the free parameters by ``draws`` seeded refits (module doc).

    Args:
        problem: evaluates whitened residuals and Jacobian at a full parameter vector.
        x: (n,) the solution x̂ [SI].
        free: indices of the fitted parameters (None: all).
        scale: the variance factor s of the whitened residuals (1: declared noise or
            residuals whitened by σ̂).
        draws: number of refits (≥ 2).
        seed: seed of the noise draws.
        progress: ``progress(done, total)`` after each refit (each chunk in parallel).
        n_jobs: worker processes (joblib; -1 = every CPU); used only with ``factory``.
        factory: a picklable callable that rebuilds ``problem`` in a worker.

    Raises:
        PincalError: ``draws`` is not an integer ≥ 2.
    """
    draws = check_draws(draws)
    x = np.asarray(x, dtype=float)
    idx = np.arange(x.size) if free is None else np.asarray(free, dtype=int)
    r0 = np.asarray(problem.evaluate(x, jacobian=True)[0], dtype=float)
    rng = np.random.default_rng(seed)
    shifts = -r0 + scale * rng.standard_normal((draws, r0.size))
    if factory is not None and n_jobs != 1:
        from joblib import Parallel, cpu_count, delayed

        workers = min(cpu_count() if n_jobs == -1 else n_jobs, draws)
        parts = np.array_split(np.arange(draws), max(workers, 1))
        done = 0
        fits: list[np.ndarray | None] = []
        chunks = Parallel(n_jobs=workers, return_as="generator")(
            delayed(_worker)(factory, x, idx, r0, shifts[p]) for p in parts
        )
        for p, chunk in zip(parts, chunks, strict=True):
            fits += _refits(problem, x, idx, shifts[p]) if chunk is None else chunk
            done += len(chunk)
            if progress is not None:
                progress(done, draws)
    else:
        fits = []
        for b in range(draws):
            fits += _refits(problem, x, idx, shifts[b : b + 1])
            if progress is not None:
                progress(b + 1, draws)
    good = [f for f in fits if f is not None]
    D = np.array(good).reshape(len(good), idx.size)
    cov = D.T @ D / max(len(good) - 1, 1) if len(good) >= 2 else np.full((idx.size,) * 2, np.nan)
    return Bootstrap(cov, len(good), draws - len(good), seed)
