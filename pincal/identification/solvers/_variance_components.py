"""Variance-component estimation: the noise σ of each block from the residuals.

When no noise is declared the σ of each block b (position, orientation) is estimated
from the residuals (Helmert / Förstner variance-component estimation):

    σ_b² = r_bᵀ r_b / (n_b − tr(H_bb)),   H = J_w (J_wᵀ J_w)⁺ J_wᵀ,

r_b the raw residuals of the block's n_b equations at the fit with the current σ and
n_b − tr(H_bb) the block's redundancy (its equations not used up by the fit; with a
prior, H is the regularised fit's: :func:`pincal.identification._weighting.data_leverage`).
With a robust loss, equations whose whitened residual exceeds 3 are left out of the
estimate (and the sum is corrected for the truncated Gaussian tail).

:func:`settle_linearised` iterates the estimate on the fit linearised at a solution
(no kinematics), so that the fit (:func:`pincal.identification.solvers._noise.weighted_fit`) is
repeated only once the estimate has settled there.
"""

from __future__ import annotations

import numpy as np

from pincal.errors import NoiseEstimationError
from pincal.identification._weighting import (
    INLIER_LIMIT,
    TRUNCATED_VARIANCE,
    data_leverage,
    robust_weights,
)
from pincal.identification.problem import CalibrationProblem

__all__ = [
    "MAX_ROUNDS",
    "RATIO_RTOL",
    "RTOL",
    "initial_weights",
    "ratio_change",
    "settle_linearised",
    "variance_components",
]

#: largest number of re-weighted fits of the noise estimation
MAX_ROUNDS = 30
#: with a robust loss, the estimate has settled when no block's σ changes by more than
#: this (relative) between two fits
RTOL = 1e-3
#: least squares: the estimate has settled when the ratio of the blocks' σ changes by at
#: most this (relative) between two fits. The weighted least-squares solution moves by
#: about this fraction of its standard deviations per relative change of the ratio, so
#: the next re-fit would move the parameters by ~1 % of their σ: well inside their
#: uncertainty, and not worth another fit
RATIO_RTOL = 1e-2


def initial_weights(
    model: CalibrationProblem, J0: np.ndarray, raw0: np.ndarray
) -> tuple[CalibrationProblem, np.ndarray]:
    """Start weights of a model whose noise is to be estimated, and J0 re-weighted.

    σ_b starts at the RMS of the block's residuals at the start values (floored), so the
    first fit weighs the blocks as their model errors; the estimation then refines it.

    Args:
        model: residual model.
        J0: (N, n) its whitened Jacobian at the start values, N = m·k.
        raw0: (m, k) raw residuals at the start values [m, rad].

    Returns:
        The (re-weighted) model and J0 in its weights; unchanged when noise is known.
    """
    if model.known_noise:
        return model, J0
    std = {
        b: max(float(np.sqrt(np.mean(raw0[:, cols] ** 2))), model.sigma_floor)
        for b, cols in model.blocks.items()
    }
    new = model.with_block_std(std)
    scale = (model.sigma / new.sigma).ravel()
    return new, J0 * scale[:, None]


def variance_components(
    model: CalibrationProblem,
    raw: np.ndarray,
    J_w: np.ndarray,
    loss: str = "linear",
    prior: np.ndarray | None = None,
) -> tuple[dict[str, float], dict[str, float]]:
    """One variance-component update: σ_b² = r_bᵀr_b / (n_b − tr(H_bb)) per block.

    Args:
        model: the residual model at its current weights.
        raw: (m, k) raw residuals [m, rad].
        J_w: (N, p) whitened Jacobian of the fitted parameters, N = m·k.
        loss: with a robust loss, equations beyond 3σ are left out.
        prior: (p,) prior weights 1/σ of the fitted parameters (0: none), or None: H
            is then the regularised fit's (:func:`data_leverage`).

    Returns:
        ({block: σ [m or rad]}, {block: redundancy n_b − tr(H_bb)}).

    Raises:
        NoiseEstimationError: a block has less than one redundant equation.
    """
    z = (raw / model.sigma).ravel()
    keep = np.ones(z.size, dtype=bool) if loss == "linear" else np.abs(z) <= INLIER_LIMIT
    h = np.zeros(z.size)
    h[keep] = data_leverage(J_w[keep], prior)
    col = np.tile(np.arange(raw.shape[1]), raw.shape[0])
    flat = raw.ravel()
    std, red = {}, {}
    for b, cols in model.blocks.items():
        sel = keep & np.isin(col, cols)
        red[b] = float(np.sum(1.0 - h[sel]))
        if red[b] < 1.0:
            raise NoiseEstimationError(
                f"cannot estimate the {b} noise: its {int(sel.sum())} equations leave "
                f"{red[b]:.2f} redundant after the fit (need ≥ 1); declare the instrument "
                "noise (noise= argument, `--noise pos_mm,ori_mrad` or a '# noise:' header) "
                "or measure more poses"
            )
        var = float(np.sum(flat[sel] ** 2)) / red[b]
        if loss != "linear":
            var /= TRUNCATED_VARIANCE
        std[b] = max(float(np.sqrt(var)), model.sigma_floor)
    return std, red


def ratio_change(new: dict[str, float], old: dict[str, float]) -> float:
    """Relative change of the ratio of the blocks' σ (0 for one block)."""
    q = [new[b] / old[b] for b in new]
    return max(q) / min(q) - 1.0


def _linear_step(
    A: np.ndarray,
    b: np.ndarray,
    loss: str,
    f_scale: float,
    prior: tuple[np.ndarray, np.ndarray] | None,
) -> np.ndarray:
    """The step δ of the linearised fit: min Σ ρ((b + Aδ)²) (+ ½‖w_p·δ + c‖² of a prior).

    ``A`` (N, p) and ``b`` (N,) whitened; ``prior`` (w_p (p,), c (p,)) its weights and its
    residual at the current point, or None. A robust loss is solved by iteratively
    re-weighted least squares on the data's rows (the prior's stay Gaussian).
    """
    n = b.size
    if prior is not None:
        A, b = np.vstack([A, np.diag(prior[0])]), np.concatenate([b, prior[1]])
    u = np.ones(b.size)
    step = np.zeros(A.shape[1])
    for _ in range(MAX_ROUNDS if loss != "linear" else 1):
        s = np.sqrt(u)
        step = -np.linalg.lstsq(A * s[:, None], b * s, rcond=None)[0]
        new = np.ones(b.size)
        new[:n] = robust_weights(loss, (b + A @ step)[:n], f_scale)
        if np.max(np.abs(new - u)) <= 1e-6:
            break
        u = new
    return step


def settle_linearised(
    model: CalibrationProblem,
    raw: np.ndarray,
    J_w: np.ndarray,
    std: dict[str, float],
    loss: str = "linear",
    f_scale: float = float("nan"),
    prior: tuple[np.ndarray, np.ndarray] | None = None,
) -> dict[str, float]:
    """Variance components iterated on the fit linearised at the current solution.

    Args:
        model: the residual model the solution was fitted with (its ``sigma`` whitens
            ``J_w``).
        raw: (m, k) raw residuals at the solution [m, rad].
        J_w: (N, p) whitened Jacobian of the fitted parameters there.
        std: the first estimate {block: σ} from ``raw``.
        loss: the fit's loss.
        f_scale: its soft margin [σ] (a robust loss).
        prior: (1/σ (p,), residual w·(x − mean) (p,)) of the fitted parameters' prior
            at the solution, or None.

    Returns:
        {block: σ} that no longer changes on the linearised fit: their ratio by at most
        ``RATIO_RTOL`` (least squares without a prior), else each by at most ``RTOL``.
    """
    J_raw = J_w * model.sigma.reshape(-1)[:, None]  # Jacobian of the raw residuals
    r0 = raw.reshape(-1)
    ratio_only = loss == "linear" and prior is None
    weights = None if prior is None else prior[0]
    for _ in range(MAX_ROUNDS):
        trial = model.with_block_std(std)
        w = 1.0 / trial.sigma.reshape(-1)
        A = J_raw * w[:, None]
        step = _linear_step(A, r0 * w, loss, f_scale, prior)
        lin = (r0 + J_raw @ step).reshape(raw.shape)
        new, _ = variance_components(trial, lin, A, loss, weights)
        if ratio_only:
            change, tol = ratio_change(new, std), RATIO_RTOL
        else:
            change, tol = max(abs(new[b] / std[b] - 1.0) for b in new), RTOL
        std = new
        if change <= tol:
            break
    return std
