"""Fitting with declared or estimated noise: variance-component estimation.

Real measurement files rarely declare their noise. Fitting them with unit weights
would weigh 1 m like 1 rad and make the covariance meaningless, so when no noise is
declared the σ of each block b (position, orientation) is estimated from the
residuals and the fit repeated until the estimate settles (Helmert / Förstner
variance-component estimation):

    σ_b² = r_bᵀ r_b / (n_b − tr(H_bb)),   H = J_w (J_wᵀ J_w)⁺ J_wᵀ,

r_b the raw residuals of the block's n_b equations at the fit with the current σ and
n_b − tr(H_bb) the block's redundancy (its equations not used up by the fit). With a
robust loss, equations whose whitened residual exceeds 3 are left out of the estimate
(and the sum is corrected for the truncated Gaussian tail).

Without a prior, only the ratio of the blocks' σ changes the fit (a common factor
scales the cost, not its minimum); with a robust loss (its margin is in σ) or a
Gaussian prior (``prior_std`` of the options: the cost is Σ(r/σ)² + Σ((x − mean)/σ_p)²)
σ itself does. With a local solver the estimate is first iterated without re-fitting:
on the fit linearised at the current solution (the Jacobian and residuals already
evaluated there, a robust loss by re-weighted least squares; no kinematics), until it
settles — the ratio by at most :data:`RATIO_RTOL` (1 %) for least squares without a
prior, each σ by at most :data:`RTOL` (0.1 %) otherwise; only then is the model
re-fitted, warm-started from the current solution, and the estimate checked once more
on the re-fitted residuals by the same rule (one block, least squares, no prior: after
one fit). A well-posed problem so needs two fits in all, and the data and a prior are
weighed by the noise the fit leaves, not by the start residuals' RMS.
"""

from __future__ import annotations

import logging

import numpy as np

from pincal.errors import NoiseEstimationError
from pincal.identification._options import GaussNewtonOptions, LMOptions
from pincal.identification._outcome import Progress, SolverOutcome
from pincal.identification._problem import TRIAL_FAILURES, CalibrationProblem
from pincal.identification._result import LocalSolverExtras
from pincal.identification._solvers import Solver, SolverOptions
from pincal.identification._weighting import (
    INLIER_LIMIT,
    ROBUST_F_SCALE,
    TRUNCATED_VARIANCE,
    Weighting,
    data_leverage,
    robust_weights,
)

__all__ = [
    "MAX_ROUNDS",
    "RATIO_RTOL",
    "RTOL",
    "initial_weights",
    "variance_components",
    "weighted_fit",
]

log = logging.getLogger(__name__)
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


def _ratio_change(new: dict[str, float], old: dict[str, float]) -> float:
    """Relative change of the ratio of the blocks' σ (0 for one block)."""
    q = [new[b] / old[b] for b in new]
    return max(q) / min(q) - 1.0


def _linear_step(
    A: np.ndarray, b: np.ndarray, loss: str, f_scale: float, prior: tuple | None
) -> np.ndarray:
    """The step δ of the linearised fit: min Σ ρ((b + Aδ)²) (+ ½‖w_p·δ + c‖² of a prior).

    ``A`` (N, p) and ``b`` (N,) whitened; ``prior`` (w_p (p,), c (p,)) its weights and its
    residual at the current point, or None. A robust loss is solved by iteratively
    re-weighted least squares on all rows (scipy's losses apply to the prior rows too).
    """
    if prior is not None:
        A, b = np.vstack([A, np.diag(prior[0])]), np.concatenate([b, prior[1]])
    u = np.ones(b.size)
    step = np.zeros(A.shape[1])
    for _ in range(MAX_ROUNDS if loss != "linear" else 1):
        s = np.sqrt(u)
        step = -np.linalg.lstsq(A * s[:, None], b * s, rcond=None)[0]
        new = robust_weights(loss, b + A @ step, f_scale)
        if np.max(np.abs(new - u)) <= 1e-6:
            break
        u = new
    return step


def _settle_linearised(
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
            change, tol = _ratio_change(new, std), RATIO_RTOL
        else:
            change, tol = max(abs(new[b] / std[b] - 1.0) for b in new), RTOL
        std = new
        if change <= tol:
            break
    return std


def _loss(opts: object) -> tuple[str, float]:
    loss = str(getattr(opts, "loss", "linear"))
    if loss == "linear":
        return loss, float("nan")
    f = getattr(opts, "f_scale", None)
    return loss, float(ROBUST_F_SCALE[loss] if f is None else f)


def robust_cost(loss: str, r_w: np.ndarray, f_scale: float) -> float:
    """The robust cost ``½ f² Σ ρ((r/f)²)`` of scipy's losses for whitened residuals [σ²]."""
    z = (np.asarray(r_w, dtype=float).ravel() / f_scale) ** 2
    if loss == "huber":
        rho = np.where(z <= 1.0, z, 2.0 * np.sqrt(z) - 1.0)
    elif loss == "soft_l1":
        rho = 2.0 * (np.sqrt(1.0 + z) - 1.0)
    elif loss == "cauchy":
        rho = np.log1p(z)
    elif loss == "arctan":
        rho = np.arctan(z)
    else:
        rho = z
    return 0.5 * f_scale**2 * float(np.sum(rho))


def _robust_progress(
    model: CalibrationProblem,
    x0: np.ndarray,
    x: np.ndarray,
    r_w: np.ndarray,
    loss: str,
    f_scale: float,
    out: SolverOutcome,
    opts: SolverOptions | None = None,
) -> SolverOutcome:
    """``out`` with success False when the robust fit ends worse than its start.

    Both ends are scored with the final weights: the robust cost, and — since a robust
    cost can fall by giving up on most poses — the median whitened residual norm per pose.
    With a Gaussian prior (``prior_std``/``prior_mean`` of the options) the objective is
    the robust cost plus the prior's ½Σ((x − mean)/σ)², and the median is not asked to
    fall: the prior pulls the fit away from the data by design.
    """
    try:
        _, _, raw0 = model.evaluate(x0)
    except TRIAL_FAILURES:
        return out
    r0 = raw0 / model.sigma
    c0, c1 = robust_cost(loss, r0, f_scale), robust_cost(loss, r_w, f_scale)
    m0 = float(np.median(np.linalg.norm(r0, axis=1)))
    m1 = float(np.median(np.linalg.norm(r_w, axis=1)))
    if isinstance(opts, (GaussNewtonOptions, LMOptions)) and opts.prior_std is not None:
        mean, sd = np.asarray(opts.prior_mean), np.asarray(opts.prior_std)
        c0 += 0.5 * float(np.sum(((np.asarray(x0) - mean) / sd) ** 2))
        c1 += 0.5 * float(np.sum(((np.asarray(x) - mean) / sd) ** 2))
        m1 = min(m1, m0)
    # a fit re-started at its own solution ends where it began, to the solver's jitter
    # (~1e-3 of the median): that is no worse; giving up on poses moves it by far more
    if c1 <= c0 * (1 + 1e-6) and m1 <= m0 * (1 + 1e-3):
        return out
    msg = (
        f"the {loss} fit ended worse than its start (robust cost {c0:.6g} → {c1:.6g}, median "
        f"pose residual {m0:.4g}σ → {m1:.4g}σ); not a solution: try --loss huber or a "
        f"least-squares fit first. Solver said: {out.message}"
    )
    log.warning(msg)
    return SolverOutcome(out.x, out.iterations, out.history, False, msg, out.extras, out.fitted)


def weighted_fit(
    model: CalibrationProblem,
    entry: Solver,
    x0: np.ndarray,
    free: np.ndarray,
    opts: SolverOptions,
    progress: Progress = None,
) -> tuple[SolverOutcome, CalibrationProblem, Weighting]:
    """Run the solver; when the noise is estimated, re-weight and re-fit until it settles.

    Later rounds run the same local solver (``gauss-newton``, ``lm``) from the previous
    solution. A global or planned search (``qpso``, ``qpso-stepwise``, ``step-planned``)
    runs once, weighted by the start weights of :func:`initial_weights`; the σ and the
    covariance are then estimated from its residuals (one round: re-fit with a local
    solver for the converged estimate).

    Args:
        model: residual model (re-weighted by :func:`initial_weights` when estimating).
        entry: the registered solver.
        x0: (n,) start values [SI].
        free: (p,) integer indices into the n parameters of those to fit.
        opts: the solver's options dataclass.
        progress: optional ``(iteration, cost)`` callback passed to the solver.

    Returns:
        (outcome over all rounds, the final residual model, its :class:`Weighting`).

    Raises:
        NoiseEstimationError: a block cannot be estimated (too few redundant equations).
    """
    estimating = model.noise_source == "estimated"
    loss, f_scale = _loss(opts)
    local = entry.name in ("gauss-newton", "lm")
    x, rounds, iterations, history = x0, 0, 0, []
    converged = not estimating
    red: dict[str, float] = {}
    first, evaluations, rejected = None, 0, 0
    weights = (
        opts.prior_weights(x0.size) if isinstance(opts, (GaussNewtonOptions, LMOptions)) else None
    )
    ratio_only = loss == "linear" and weights is None  # σ's common factor leaves the fit alone
    tol = RATIO_RTOL if ratio_only else RTOL
    while True:
        out = entry.solve(model, x, free, opts, progress)
        first = first or out
        if isinstance(out.extras, LocalSolverExtras):
            evaluations += out.extras.evaluations
            rejected += out.extras.rejected_steps
        rounds += 1
        iterations += out.iterations
        history += list(out.history)
        x = out.x
        fitted = free if out.fitted is None else np.asarray(out.fitted, dtype=int)
        _, J, raw = model.evaluate(x)
        if not estimating:
            break
        prior = None if weights is None else weights[0][fitted]
        std, red = variance_components(model, raw, J[:, fitted], loss, prior)
        old = model.block_std()
        exact = all(v <= model.sigma_floor for v in std.values())
        if ratio_only:  # only the ratio moves the fit
            change = _ratio_change(std, old)
        else:  # a robust loss or a prior: σ itself does
            change = max(abs(std[b] / old[b] - 1.0) for b in std)
        if local and not exact and change > tol:  # settle it first without kinematics
            held = None
            if prior is not None:
                assert weights is not None
                held = (prior, prior * (x[fitted] - weights[1][fitted]))
            std = _settle_linearised(model, raw, J[:, fitted], std, loss, f_scale, held)
        log.info("noise estimate round %d: %s (change %.2g)", rounds, std, change)
        new = model.with_block_std(std)
        J = J * (model.sigma / new.sigma).reshape(-1)[:, None]
        model = new
        if change <= tol or exact:
            # settled (one block and least squares: at once, σ does not move the fit);
            converged = True  # or data fitted to the solver's precision
            break
        if rounds >= MAX_ROUNDS or not local:
            break  # a global / planned search is run once (start weights, then estimated)
        if rounds >= 2 and not out.success:
            break  # two fits in a row did not converge: more weights will not help
    r_w = raw / model.sigma
    if not red:  # the declared noise's redundancy, as an estimate would count it
        prior = None if weights is None else weights[0][fitted]
        h = data_leverage(J[:, fitted], prior).reshape(raw.shape)
        red = {b: float(np.sum(1.0 - h[:, cols])) for b, cols in model.blocks.items()}
    std_now = model.block_std()
    pose_w = robust_weights(loss, r_w, f_scale).min(axis=1) if loss != "linear" else None
    weighting = Weighting(
        source=model.noise_source,
        position_std=std_now.get("position", float("nan")),
        orientation_std=std_now.get("orientation", float("nan")),
        rounds=rounds if estimating else 0,
        converged=converged,
        redundancy=red,
        loss=loss,
        f_scale=f_scale,
        pose_weights=np.ones(raw.shape[0]) if pose_w is None else pose_w,
        whitened=r_w,
    )
    if loss != "linear" and out.success:
        out = _robust_progress(model, x0, x, r_w, loss, f_scale, out, opts)
    if estimating:
        note = (
            f"noise estimated from the residuals in {rounds} re-weighted fits"
            + ("" if converged else f" (not settled to {tol:g} after {rounds})")
            + "; "
        )
        extras = first.extras  # a global solver's own extras; local ones summed
        if isinstance(out.extras, LocalSolverExtras):
            extras = LocalSolverExtras(evaluations, rejected, out.extras.damping)
        out = SolverOutcome(
            x, iterations, tuple(history), out.success, note + out.message, extras, out.fitted
        )
    return out, model, weighting
