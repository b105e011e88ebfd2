"""What the misspecification probes cannot see: their detection floor on this design.

A probe (:mod:`pincal.identification.gate._misspecification`) fires when its F-test has a
p-value below the gate's Bonferroni level α *and* its term explains at least a share
``e`` of the residual of the blocks it acts on. For a true error of size ``s`` along one
of the probe's columns ``b`` (whitened, after projecting out the fitted parameters),
the reduction of the residual sum of squares is non-central χ²(q, λ) with
``λ = s² ‖b‖²``, and

* the F statistic is non-central F(q, ν − q, λ): P(F > F_crit | λ) = power;
* the explained share exceeds ``e`` when ΔRSS ≥ e/(1 − e) · (ν_t − q), ν_t the
  redundancy of the blocks the probe acts on (the rest of their residual at its mean).

:func:`detection_floor` finds the smallest λ that reaches the power (90 %) on both and
returns the size ``s = √λ / ‖b‖`` for the column the probe sees worst (the largest such
size: any error above it along one column is caught with that power). With the noise
*estimated*, σ̂ absorbs what the probes do not catch, so this floor is what the fit
cannot judge: errors below it pass unseen; a declared noise judges the fit against it.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["POWER", "detection_floor", "floor_lambda"]

#: detection probability the floor is computed for
POWER = 0.9


def _power(lam: float, q: int, dof: int, f_crit: float, need: float) -> float:
    """P(both tests fire | λ): the F-test's and the explained share's (the smaller)."""
    from scipy import special

    p_f = 1.0 - float(special.ncfdtr(q, dof, lam, f_crit))
    p_e = 1.0 - float(special.chndtr(need, q, lam)) if need > 0 else 1.0
    return min(p_f, p_e)


def floor_lambda(q: int, dof: int, alpha: float, share: float, nu_t: float) -> float:
    """The non-centrality λ at which the probe fires with probability :data:`POWER`.

    Args:
        q: the probe's columns.
        dof: ν − q, the F-test's denominator degrees of freedom.
        alpha: the gate's per-probe significance (Bonferroni).
        share: the share of the residual the term must explain (``probe_explained``).
        nu_t: redundancy of the blocks the probe acts on.
    """
    from pincal.identification._distributions import f_isf

    f_crit = f_isf(alpha, q, dof)
    need = share / (1.0 - share) * max(nu_t - q, 0.0) if share < 1 else math.inf
    lo, hi = 0.0, 1.0
    while _power(hi, q, dof, f_crit, need) < POWER:
        lo, hi = hi, 2 * hi
        if hi > 1e12:
            return math.inf
    for _ in range(60):  # bisection to ~1e-18 relative
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _power(mid, q, dof, f_crit, need) < POWER else (lo, mid)
    return hi


def detection_floor(
    B: np.ndarray, q: int, dof: int, alpha: float, share: float, nu_t: float
) -> float:
    """Smallest size of an error along the probe's worst-seen column caught at :data:`POWER`.

    Args:
        B: (N, c) the probe's whitened columns after projecting out the fitted
            parameters (per unit of the probe's coefficient: a unit scale, gain, a
            1 m drift over the pose order, a 1 m or 1 rad trend).
        q: the probe's columns.
        dof: ν − q, the F-test's denominator degrees of freedom.
        alpha: the gate's per-probe significance (Bonferroni).
        share: the share of the residual the term must explain.
        nu_t: redundancy of the blocks the probe acts on.

    Returns:
        The size in the coefficient's unit (NaN when B has no column; inf when no
        error size reaches the power: the probe cannot fire on this design).
    """
    norms = np.linalg.norm(np.atleast_2d(B), axis=0)
    norms = norms[norms > 0]
    if not norms.size:
        return float("nan")
    lam = floor_lambda(q, dof, alpha, share, nu_t)
    return float(math.sqrt(lam) / np.min(norms))
