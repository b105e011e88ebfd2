"""A finished marker fit linearised at its solution: what it predicts without some rows.

Cross-validation refits a procedure on K − 1 folds, K times. Near a solution the fit's
cost is the weighted least-squares cost of its linearisation (the fitted set, the robust
loss' weights and the prior kept), whose minimum without a fold's rows is one linear
solve away:

    N = Jᵀ W J + P,   N₋F = N − J_Fᵀ W_F J_F,   δx = N₋F⁻¹ J_Fᵀ W_F r_F,

and the fold's residuals predicted by the fit that did not see them are r_F + J_F δx
(r = measured − model, whitened; J = ∂r/∂x; W the loss' weights ρ'; P the prior's
precision). This is exact for a linear model and the first-order (one Newton step)
leave-fold-out of a nonlinear one — the approximate cross-validation of generalised
cross-validation and its leave-one-out relatives. It costs one Jacobian per fit instead
of K refits, which is what choosing a prior's strength among several candidates needs;
a figure of held-out error that a user reads comes from real refits
(:func:`pincal.validation.cross_validate`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pincal.identification._marker_fit import MarkerFit, _problem
from pincal.identification._weighting import robust_weights
from pincal.measure import MarkerSetup, Measurements, marker_mechanisms

__all__ = ["LinearisedFit", "linearise_marker_fit"]


@dataclass(frozen=True)
class LinearisedFit:
    """A finished fit linearised at its solution, row by row.

    Attributes:
        residuals: (N,) whitened residuals (measured − model)/σ at the solution.
        jacobian: (N, f) their derivatives in the f fitted unknowns [1/SI].
        sigma: (N,) each row's σ [m, rad].
        weights: (N,) each row's robust-loss weight ρ' (1 for least squares).
        precision: (f,) the prior's precision 1/s² on each fitted unknown [1/SI²]
            (0 where there is none).
        pose: (N,) each row's pose (row of the data file).
        marker: (N,) each row's marker (measurement set).
        component: (N,) each row's component: 0–2 position x y z, 3–5 rotation.
    """

    residuals: np.ndarray
    jacobian: np.ndarray
    sigma: np.ndarray
    weights: np.ndarray
    precision: np.ndarray
    pose: np.ndarray
    marker: np.ndarray
    component: np.ndarray

    def without(self, poses: np.ndarray) -> np.ndarray:
        """(N,) raw residuals [m, rad] of every row as the fit without ``poses`` predicts them.

        Args:
            poses: the pose indices left out of the fit.
        """
        J, r, w = self.jacobian, self.residuals, self.weights
        out = np.isin(self.pose, poses)
        JF = J[out]
        normal = J.T @ (w[:, None] * J) + np.diag(self.precision) - JF.T @ (w[out, None] * JF)
        step = np.linalg.lstsq(normal, JF.T @ (w[out] * r[out]), rcond=None)[0]
        return (r + J @ step) * self.sigma


def linearise_marker_fit(
    fit: MarkerFit, setup: MarkerSetup, meas: Measurements | tuple[Measurements, ...]
) -> LinearisedFit:
    """The fit of ``meas`` (one set, or one per marker) linearised at its solution.

    The rows are weighted as the fit weighted them: its noise σ per block (declared or
    estimated), its robust loss' weights at the solution and its prior.
    """
    res = fit.result
    parts = (meas,) if isinstance(meas, Measurements) else tuple(meas)
    reg = fit.registration.mechanism
    start = reg if len(parts) == 1 else marker_mechanisms(reg, setup)
    x = res.full_values
    model = _problem(start, res.parameter_set, meas if len(parts) > 1 else parts[0],
                     list(res.parameter_set.names), x).model  # fmt: skip
    w = res.weighting
    if not model.known_noise and w is not None:
        std = {"position": w.position_std, "orientation": w.orientation_std}
        model = model.with_block_std({b: std[b] for b in model.blocks})
    r, J, _ = model.evaluate(x, True)
    cols = np.flatnonzero(res.identified)
    loss, scale = ("linear", 1.0) if w is None else (w.loss, w.f_scale)
    precision = np.zeros(cols.size) if res.prior is None else res.prior[0][cols] ** 2
    m, k = len(parts[0]), len(model.rows)
    return LinearisedFit(
        residuals=np.asarray(r),
        jacobian=np.asarray(J)[:, cols],
        sigma=np.asarray(model.sigma, dtype=float).reshape(-1),
        weights=robust_weights(loss, np.asarray(r), scale),
        precision=precision,
        pose=np.tile(np.repeat(np.arange(m), k), len(parts)),
        marker=np.repeat(np.arange(len(parts)), m * k),
        component=np.tile(np.asarray(model.rows), m * len(parts)),
    )
