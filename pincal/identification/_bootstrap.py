"""Parametric bootstrap of a fit: its uncertainty where the linearisation does not hold.

When :func:`pincal.identification._linearity.check_linearity` finds the model
non-linear over its confidence region, ``s²·(JᵀJ)⁻¹`` is not the fit's covariance.
:func:`bootstrap_covariance` measures it instead: new data are drawn from the fitted
model with the fit's noise, ``y* = f(x̂) + s·σ·ε``, and refitted from x̂. In whitened
residuals that needs nothing but the problem's own evaluation:

    r*(x) = (y* − f(x)) / σ = r(x) − r(x̂) + s·ε,   ε ~ N(0, I),

so any object with ``evaluate(x, jacobian=True) -> (r, J, ...)`` — a pose problem or a
scalar-instrument problem — can be bootstrapped. Each refit is a damped Gauss–Newton
(Levenberg–Marquardt) on the free parameters. Seeded; the spread of the refits about
x̂ is the covariance. :func:`widened` combines it with the linear one: each σ is the
larger of the two, the correlations are the bootstrap's.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from pincal.identification._linearity import TRIAL_ERRORS, ResidualModel

__all__ = ["Bootstrap", "bootstrap_covariance", "widened"]

DRAWS = 100
_MAX_ITERATIONS = 100
_CONVERGED = 1e-8  # a step that would lower ‖r‖² by less than this: converged (whitened)


@dataclass(frozen=True)
class Bootstrap:
    """A parametric bootstrap of a fit.

    Attributes:
        covariance: (n_free, n_free) covariance of the refits about x̂ [SI].
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


def bootstrap_covariance(
    problem: ResidualModel,
    x: np.ndarray,
    free: np.ndarray | None = None,
    *,
    scale: float = 1.0,
    draws: int = DRAWS,
    seed: int = 0,
    progress: Callable[[int, int], None] | None = None,
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
        progress: ``progress(done, total)`` after each refit.
    """
    x = np.asarray(x, dtype=float)
    idx = np.arange(x.size) if free is None else np.asarray(free, dtype=int)
    r0 = np.asarray(problem.evaluate(x, jacobian=True)[0], dtype=float)
    rng = np.random.default_rng(seed)
    fits, failed = [], 0
    for b in range(max(int(draws), 2)):
        shift = -r0 + scale * rng.standard_normal(r0.size)
        xb = _refit(problem, x, idx, shift)
        if xb is None or not np.all(np.isfinite(xb)):
            failed += 1
        else:
            fits.append(xb[idx] - x[idx])
        if progress is not None:
            progress(b + 1, draws)
    D = np.array(fits).reshape(len(fits), idx.size)
    cov = D.T @ D / max(len(fits) - 1, 1) if len(fits) >= 2 else np.full((idx.size,) * 2, np.nan)
    return Bootstrap(cov, len(fits), failed, seed)


def widened(linear: np.ndarray, boot: Bootstrap) -> np.ndarray:
    """Covariance with each σ the larger of the linear and bootstrap one.

    The correlations are the bootstrap's; without usable refits, the linear covariance.
    """
    lin = np.asarray(linear, dtype=float)
    sb = boot.std
    if boot.draws < 2 or not np.all(np.isfinite(sb)):
        return lin
    s = np.maximum(np.sqrt(np.clip(np.diag(lin), 0.0, None)), sb)
    with np.errstate(divide="ignore", invalid="ignore"):
        corr = boot.covariance / np.outer(sb, sb)
    corr = np.where(np.isfinite(corr), corr, 0.0)
    np.fill_diagonal(corr, 1.0)
    return corr * np.outer(s, s)
