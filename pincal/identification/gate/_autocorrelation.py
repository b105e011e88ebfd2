"""Serially correlated residuals along the pose order: named as such, not as a drift.

Errors that wander slowly while the poses are measured (an instrument's warm-up, air
turbulence, a thermal breathing of the machine) make neighbouring poses' residuals
alike: an AR(1) process ``e_t = ρ e_{t−1} + w_t``. A linear drift makes them alike too,
so the drift probe fires on both; what tells them apart is what remains once the drift
is fitted: nothing for a drift, the correlation for an AR(1) error.

:func:`serial_correlation` fits the model's columns and the nuisance (drift) columns to
the whitened residuals, and pools the lag-1 autocorrelation of what remains over the
measured components,

    ρ̂ = Σ_c Σ_t r_{t,c} r_{t−1,c} / Σ_c Σ_t r_{t,c}²,
    Durbin–Watson d = Σ (r_t − r_{t−1})² / Σ r_t² ≈ 2 (1 − ρ̂),

with the one-sided p-value of ``ρ̂ √(k (m − 1))`` against N(0, 1) (independent
residuals: ρ̂ ≈ 0, d ≈ 2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from statistics import NormalDist

import numpy as np

from pincal.identification.gate._outliers import column_basis

__all__ = ["SerialCorrelation", "serial_correlation"]


@dataclass(frozen=True)
class SerialCorrelation:
    """Lag-1 autocorrelation of the residuals along the pose order.

    Attributes:
        rho: pooled lag-1 autocorrelation ρ̂ (dimensionless).
        durbin_watson: d (≈ 2 for independent residuals, → 0 for strong correlation).
        p_value: one-sided P(ρ̂ this large | independent residuals).
    """

    rho: float
    durbin_watson: float
    p_value: float

    def describe(self) -> str:
        """One sentence for the report: the lag-1 autocorrelation, its test, and what to do."""
        return (
            f"residuals correlated along the pose order: lag-1 autocorrelation "
            f"{self.rho:.2f} (Durbin–Watson {self.durbin_watson:.2f}, p = {self.p_value:.2g}), "
            f"also with a linear drift fitted — serially correlated errors (an instrument "
            f"or machine wandering while the poses were measured), not a drift: the "
            f"uncertainty assumes independent poses; measure in a shuffled order or "
            f"shorten the campaign"
        )


def serial_correlation(
    A: np.ndarray, z: np.ndarray, nuisance: np.ndarray | None = None
) -> SerialCorrelation | None:
    """The lag-1 autocorrelation of the residuals once the model and ``nuisance`` are fitted.

    Args:
        A: (m, k, p) whitened Jacobian of the fitted parameters (m poses in their order).
        z: (m, k) whitened residuals.
        nuisance: (m, k, c) whitened nuisance columns fitted too (the drift), or None.

    Returns:
        The statistic, or None with fewer than 3 poses or no residual left.
    """
    m, k = z.shape
    if m < 3:
        return None
    cols = A.reshape(m * k, -1)
    if nuisance is not None:
        cols = np.concatenate([cols, nuisance.reshape(m * k, -1)], axis=1)
    U = column_basis(cols)
    r = z.ravel() - U @ (U.T @ z.ravel())
    r = r.reshape(m, k)
    total = float(np.sum(r**2))
    if not total > 0:
        return None
    rho = float(np.sum(r[1:] * r[:-1])) / total
    dw = float(np.sum(np.diff(r, axis=0) ** 2)) / total
    stat = rho * math.sqrt(k * (m - 1))
    return SerialCorrelation(rho, dw, 1.0 - NormalDist().cdf(stat))
