"""Fitting with declared or estimated noise: the fit re-weighted until σ settles.

Real measurement files rarely declare their noise. Fitting them with unit weights
would weigh 1 m like 1 rad and make the covariance meaningless, so when no noise is
declared the σ of each block (position, orientation) is estimated from the residuals
(:mod:`pincal.identification.solvers._variance_components`) and the fit repeated until the
estimate settles.

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

from pincal.identification._options import GaussNewtonOptions, LMOptions, f_scale
from pincal.identification._weighting import (
    Weighting,
    data_leverage,
    robust_cost,
    robust_weights,
)
from pincal.identification.problem import TRIAL_FAILURES, CalibrationProblem
from pincal.identification.results import LocalSolverExtras, Progress, SolverOutcome
from pincal.identification.solvers._solvers import Solver, SolverOptions
from pincal.identification.solvers._variance_components import (
    MAX_ROUNDS,
    RATIO_RTOL,
    RTOL,
    initial_weights,
    ratio_change,
    settle_linearised,
    variance_components,
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


def _loss(opts: object) -> tuple[str, float]:
    """(loss, its margin f [σ]) of a local solver's options; least squares otherwise."""
    if isinstance(opts, (GaussNewtonOptions, LMOptions)) and opts.loss != "linear":
        return opts.loss, f_scale(opts)
    return "linear", float("nan")


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
        prior = None if weights is None else weights[0][fitted]  # 1/σ of the fitted ones
        _, J, raw = model.evaluate(x)
        if not estimating:
            break
        std, red = variance_components(model, raw, J[:, fitted], loss, prior)
        old = model.block_std()
        exact = all(v <= model.sigma_floor for v in std.values())
        if ratio_only:  # only the ratio moves the fit
            change = ratio_change(std, old)
        else:  # a robust loss or a prior: σ itself does
            change = max(abs(std[b] / old[b] - 1.0) for b in std)
        if local and not exact and change > tol:  # settle it first without kinematics
            held = None
            if prior is not None:
                assert weights is not None
                held = (prior, prior * (x[fitted] - weights[1][fitted]))
            std = settle_linearised(model, raw, J[:, fitted], std, loss, f_scale, held)
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
