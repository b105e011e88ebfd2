"""A second-order (geodesic acceleration) correction of a Gauss–Newton step.

A parameter that the poses see only weakly at first order can be seen strongly at
second order: along the weakest direction of the excavator arm's Jacobian (singular
value ratio 1.9e-7 of its column-scaled identifiable set, scaled to a largest component
of 1) the whitened residual moves by 1.1e-2 per unit at first order and by 4.1e4 per
unit² at second order, so the exact-data cost floor is a curved valley. The
Gauss–Newton step points along the valley at the truth (9e-4 away) but a straight step
leaves it (the cost rises from 8e-6 to 1.4e-4), and the damped steps that follow shrink
mostly that direction: 50 iterations end 9e-4 off.

The correction of Transtrum and Sethna (geodesic acceleration, 2012) bends the step
along the valley: with ``r''`` the residual's second directional derivative along the
step ``δ`` (one residual evaluation, by finite differences), ``a = −A⁺ r''`` and the
trial is ``δ + a/2``. It is used only when the correction ``a/2`` is not larger than
the step itself (in the column-scaled norm); where the valley bends too fast for the
full step, the path ``x + tδ + t²a/2`` is tried at t = ½ and ¼ (the 2-RSU ankle with
``0 0`` limits: singular value ratio 7.5e-5; from cost 2.4e-7 the straight step gives
7.4e-3, the bent one 4.5e-4).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from pincal.identification.problem import TRIAL_FAILURES, ResidualModel

__all__ = ["Bent", "bent_step"]

_PROBE = 0.1  # share of the step at which the second derivative is probed
_TRUST = 4.0  # largest 2‖a‖/‖δ‖ (column-scaled): the correction a/2 not beyond the step
_LENGTHS = (1.0, 0.5, 0.25)  # points t of the path x + tδ + t²a/2 tried, in order


@dataclass(frozen=True)
class Bent:
    """The outcome of :func:`bent_step`.

    Attributes:
        values: (n,) the accepted trial values [SI], or None (no point of the path
            delivered a quarter of its predicted decrease, or the correction is not trusted).
        step: (p,) the step taken to ``values`` [SI] (zeros when none).
        cost: the cost at ``values`` (the current cost when none).
        evaluations: residual evaluations spent (the probe and the trials).
    """

    values: np.ndarray | None
    step: np.ndarray
    cost: float
    evaluations: int


def bent_step(
    model: ResidualModel,
    x: np.ndarray,
    free: np.ndarray,
    step: np.ndarray,
    A: np.ndarray,
    b: np.ndarray,
    cost: float,
    cost_of: Callable[[np.ndarray], float],
    rows: np.ndarray | None = None,
    base: float | None = None,
) -> Bent:
    """The Gauss–Newton step bent to second order, shortened along its parabola if need be.

    The trials are ``x + tδ + t²a/2`` for t = 1, ½, ¼; the first whose actual decrease is
    at least a quarter of the decrease the linear model predicts for ``tδ`` is accepted.

    Args:
        model: the residual model (whitened residuals, N of them).
        x: (n,) current values [SI].
        free: (p,) indices of the fitted values.
        step: (p,) the Gauss–Newton step δ [SI] (the least-squares step of ``A δ = −b``).
        A: (N + q, p) the step's least-squares matrix: the free columns of the whitened
            Jacobian, then q linear rows (a prior or Tikhonov term, zero second derivative).
        b: (N + q,) its right-hand side: the whitened residuals at ``x``, then the q rows'.
        cost: the cost at ``x`` (½‖b‖²).
        cost_of: the cost at a full value vector (+inf when it cannot be evaluated).
        rows: (N,) the scale of the data's rows in ``A`` and ``b`` (a robust loss'
            re-weighted model: √ρ'), or None (1).
        base: the model's value at δ = 0 when it is not ``cost`` (the re-weighted
            model's ½‖b‖²); the predicted decrease is measured from it.
    """
    none = Bent(None, np.zeros_like(step), cost, 0)
    probe = x.copy()
    probe[free] += _PROBE * step
    try:
        r_probe = model.evaluate(probe, jacobian=False)[0]
    except TRIAL_FAILURES:
        return Bent(None, none.step, cost, 1)
    n = r_probe.size
    if rows is not None:
        r_probe = r_probe * rows
    second = np.zeros(A.shape[0])
    second[:n] = (2.0 / _PROBE) * ((r_probe - b[:n]) / _PROBE - A[:n] @ step)
    if not np.all(np.isfinite(second)):
        return Bent(None, none.step, cost, 1)
    a = -np.linalg.lstsq(A, second, rcond=None)[0]
    scale = np.sqrt(np.einsum("ij,ij->j", A, A))
    if not 2.0 * np.linalg.norm(scale * a) <= _TRUST * np.linalg.norm(scale * step):
        return Bent(None, none.step, cost, 1)
    evaluations = 1
    for t in _LENGTHS:
        taken = t * step + 0.5 * t * t * a
        trial = x.copy()
        trial[free] += taken
        cost_try = cost_of(trial)
        evaluations += 1
        predicted = (cost if base is None else base) - 0.5 * float(
            np.sum((b + t * (A @ step)) ** 2)
        )
        if cost_try < cost and cost - cost_try >= 0.25 * predicted:
            return Bent(trial, taken, cost_try, evaluations)
    return Bent(None, none.step, cost, evaluations)
