"""The linear covariance, inflated along the directions where the fit is not linear.

:func:`pincal.identification.uncertainty._linearity.check_linearity` steps one σ along the principal
directions ``v_i`` of the linear covariance ``C`` (its eigenvectors, largest σ first)
and compares the cost's rise with the quadratic prediction ``½s²``. Where the rise is
only ``ρ_i`` times the prediction (ρ < 1: the valley is flatter or bends away), the
secant curvature over that σ step is ρ_i times the linear one, and the one-σ interval
of the profile along ``v_i`` is ≈ ``σ_i/√ρ_i``. :func:`inflated_covariance` scales the
variance of each such direction by ``1/ρ_i`` (the smaller ρ of the two sides), in the
eigenbasis of ``C``, and leaves every other direction — and so every correlation the
check did not question — as the linear covariance has it:

    C' = C + Σ_i (1/ρ_i − 1)·(v_iᵀ C v_i)·v_i v_iᵀ.

Nothing is estimated from a sample of refits, so the result stays a well-conditioned
covariance (its inverse is the linear one's, softened along the ``v_i``). Directions
that steepen (ρ > 1) are not shrunk; directions along which the cost could not be
evaluated or fell (ρ ≤ 0: the fit did not reach the minimum there) are not inflated
and are counted in ``unmeasured`` (their σ are then a lower bound).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pincal.identification.uncertainty._linearity import Linearity

__all__ = ["Inflation", "inflated_covariance", "widest_combination"]


@dataclass(frozen=True)
class Inflation:
    """The per-direction inflation of a linear covariance.

    Attributes:
        covariance: (k, k) the inflated covariance [SI].
        factors: (d,) σ multiplier along each direction checked (1 where not inflated).
        inflated: indices of the directions inflated (factor > 1).
        unmeasured: indices of the failing directions whose spread could not be
            measured (the cost did not rise or could not be evaluated).
    """

    covariance: np.ndarray
    factors: np.ndarray
    inflated: np.ndarray
    unmeasured: np.ndarray

    @property
    def largest(self) -> float:
        """The largest σ multiplier (1 when nothing was inflated)."""
        return float(np.max(self.factors, initial=1.0))


def inflated_covariance(covariance: np.ndarray, lin: Linearity) -> Inflation:
    """``covariance`` inflated along the directions ``lin`` finds non-linear (module doc).

    Args:
        covariance: (k, k) linear covariance of the free parameters [SI], in the order
            of ``lin.directions``' rows.
        lin: the linearity check at the solution.

    Returns:
        :class:`Inflation` (the input covariance when no direction is inflated).
    """
    C = np.asarray(covariance, dtype=float)
    d = lin.sigma.size
    factors = np.ones(d)
    unmeasured: list[int] = []
    for i in lin.offending:
        rho = lin.ratio[i]
        if not np.all(np.isfinite(rho)) or np.min(rho) <= 0.0:
            unmeasured.append(int(i))
            continue
        factors[i] = max(1.0, 1.0 / float(np.sqrt(np.min(rho))))
    inflated = np.flatnonzero(factors > 1.0)
    out = C.copy()
    if C.shape == (lin.directions.shape[0],) * 2:
        for i in inflated:
            v = lin.directions[:, i]
            out += (factors[i] ** 2 - 1.0) * float(v @ C @ v) * np.outer(v, v)
    else:  # the check's directions are not this covariance's: nothing to inflate
        inflated = np.zeros(0, dtype=int)
        factors = np.ones(d)
    return Inflation(0.5 * (out + out.T), factors, inflated, np.array(unmeasured, dtype=int))


def widest_combination(C: np.ndarray, M: np.ndarray) -> float:
    """Largest σ ratio over all combinations a·x of the covariance C + M to C.

    √(1 + λ_max) with λ the eigenvalues of M in the coordinates where C is the identity
    (directions C does not span left out); 1 when M vanishes.
    """
    if C.size == 0:
        return 1.0
    s, U = np.linalg.eigh(C)
    keep = s > 1e-12 * max(float(s.max()), 1e-300)
    W = U[:, keep] / np.sqrt(s[keep])
    lam = np.linalg.eigvalsh(W.T @ M @ W) if keep.any() else np.zeros(1)
    return math.sqrt(1.0 + max(float(lam[-1]), 0.0))
