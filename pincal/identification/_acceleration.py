"""A second-order (geodesic acceleration) correction of a Gauss–Newton step.

A parameter that the poses see only weakly at first order can be seen strongly at
second order: along the weakest direction of the excavator arm's Jacobian (singular
value ratio 1.9e-7 of its column-scaled identifiable set) the whitened residual moves by
1.1e-2 per unit at first order and by 4.1e4 per unit² at second order, so the exact-data
cost floor is a curved valley. The Gauss–Newton step points along the valley at the
truth (9e-4 away) but a straight step leaves it (the cost rises from 8e-6 to 1.4e-4), and
the damped steps that follow shrink mostly that direction: 50 iterations end 9e-4 off.

The correction of Transtrum and Sethna (geodesic acceleration, 2012) bends the step
along the valley: with ``r''`` the residual's second directional derivative along the
step ``δ`` (one residual evaluation, by finite differences), ``a = −A⁺ r''`` and the
trial is ``δ + a/2``. It is used only when the correction is small against the step
(``2‖a‖ ≤ 0.75‖δ‖`` in the column-scaled norm), i.e. when the second-order model is
trusted.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from pincal.identification._problem import TRIAL_FAILURES
from pincal.identification._residual_model import ResidualModel

__all__ = ["accelerated_trial"]

_PROBE = 0.1  # share of the step at which the second derivative is probed
_TRUST = 4.0  # largest 2‖a‖/‖δ‖ (column-scaled): the correction a/2 not beyond the step


def accelerated_trial(
    model: ResidualModel,
    x: np.ndarray,
    free: np.ndarray,
    step: np.ndarray,
    A: np.ndarray,
    r: np.ndarray,
    cost_of: Callable[[np.ndarray], float],
) -> tuple[np.ndarray, np.ndarray, float] | None:
    """The step ``δ + a/2`` corrected to second order, and the cost at its end.

    Args:
        model: the residual model (whitened residuals, N of them).
        x: (n,) current values [SI].
        free: (p,) indices of the fitted values.
        step: (p,) the Gauss–Newton (or damped) step δ [SI].
        A: (N + q, p) the step's least-squares matrix: the free columns of the whitened
            Jacobian, then q linear rows (a prior or Tikhonov term, zero second derivative).
        r: (N,) whitened residuals at ``x``.
        cost_of: the cost at a full value vector (+inf when it cannot be evaluated).

    Returns:
        (trial values (n,), the corrected step (p,), cost there), or None when the probe
        cannot be evaluated or the correction is not small against the step (two
        evaluations are spent in the first case only when the probe succeeds).
    """
    probe = x.copy()
    probe[free] += _PROBE * step
    try:
        r_probe = model.evaluate(probe, jacobian=False)[0]
    except TRIAL_FAILURES:
        return None
    n = r.size
    second = np.zeros(A.shape[0])
    second[:n] = (2.0 / _PROBE) * ((r_probe - r) / _PROBE - A[:n] @ step)
    if not np.all(np.isfinite(second)):
        return None
    a = -np.linalg.lstsq(A, second, rcond=None)[0]
    scale = np.sqrt(np.einsum("ij,ij->j", A, A))
    if not 2.0 * np.linalg.norm(scale * a) <= _TRUST * np.linalg.norm(scale * step):
        return None
    corrected = step + 0.5 * a
    trial = x.copy()
    trial[free] += corrected
    return trial, corrected, cost_of(trial)
