"""Damped Gauss–Newton, with scipy's Levenberg–Marquardt as its fallback.

Gauss–Newton that stops unconverged is re-run by Levenberg–Marquardt from its start
(:attr:`GaussNewtonOptions.fallback`): after a rejected full step its damped path can
lead a closed-loop model (a four-bar, a two-loop ankle, errors of 1 mm / 10 mrad) into
a curved valley where both crawl, where scipy's trust region, scaled by the Jacobian's
columns, goes around it from the start (measured on tests/open_world/roster.py).

Both minimise ``0.5·‖r_w(x)‖²`` of :class:`pincal.identification.CalibrationProblem`
over the free parameters, or with a robust loss ``½ f² Σ ρ((r/f)²)`` of the data's rows
(a Gaussian prior's rows stay least squares; Levenberg–Marquardt is
:mod:`pincal.identification.solvers._levenberg_marquardt`). A trial vector whose model cannot
be built or assembled (:class:`pincal.ModelFileError`, :class:`pincal.MobilityError`,
:class:`pincal.ClosureError`) or whose poses cannot be solved
(:class:`pincal.ConvergenceError`) is a rejected step, never an error.
"""

from __future__ import annotations

import logging
from collections.abc import Callable

import numpy as np

from pincal.identification._options import GaussNewtonOptions, LMOptions, f_scale
from pincal.identification._weighting import loss_derivatives, robust_cost
from pincal.identification.problem import TRIAL_FAILURES, CalibrationProblem
from pincal.identification.results import LocalSolverExtras, Progress, SolverOutcome
from pincal.identification.solvers._acceleration import Bent, bent_step
from pincal.identification.solvers._levenberg_marquardt import at_floor, levenberg_marquardt

__all__ = ["gauss_newton"]

log = logging.getLogger(__name__)
_MU_MAX = 1e10  # largest relative damping before the step is given up
_MU_OFF = 1e-7  # below it the damping is switched off (pure Gauss–Newton again)


def _decrease(
    A: np.ndarray, b: np.ndarray, step: np.ndarray, cost: float, gradient: np.ndarray | None
) -> float:
    """The decrease of the cost its quadratic model ``½‖Aδ + b‖²`` promises along ``step``.

    With a robust loss ``A``, ``b`` are scaled (:func:`loss_derivatives`) and the decrease
    is computed from the ``gradient`` of the cost, −gᵀδ − ½‖Aδ‖²: the scaled ``b`` of a
    residual beyond Huber's margin is ~1e8 and ``½‖b‖²`` would cancel to round-off.
    """
    if gradient is None:
        return cost - 0.5 * float(np.sum((b + A @ step) ** 2))
    return -float(gradient @ step) - 0.5 * float(np.sum((A @ step) ** 2))


def _second_try(
    problem: CalibrationProblem,
    x: np.ndarray,
    free: np.ndarray,
    step: np.ndarray,
    A: np.ndarray,
    b: np.ndarray,
    cost: float,
    cost_of: Callable[[np.ndarray], float],
    reweighted: tuple[np.ndarray, np.ndarray, float, np.ndarray] | None,
) -> Bent:
    """The trial after a failed full step, before damping.

    Least squares: the step bent along the residual's curvature (:func:`bent_step`). A
    robust loss: the minimiser of the re-weighted model ``reweighted`` = (A, b, its
    cost ½‖b‖²), which majorises the robust cost where the second-order model, without
    curvature for a far Huber residual, can overshoot; it must deliver a quarter of the
    decrease it promises.
    """
    if reweighted is None:
        return bent_step(problem, x, free, step, A, b, cost, cost_of)
    A_w, b_w, base, rows = reweighted
    trial = -np.linalg.lstsq(A_w, b_w, rcond=None)[0]
    values = x.copy()
    values[free] += trial
    value = cost_of(values)
    if value < cost and cost - value >= 0.25 * _decrease(A_w, b_w, trial, base, None):
        return Bent(values, trial, value, 1)
    # a curved valley: the re-weighted step bent along the residual's curvature
    bent = bent_step(problem, x, free, trial, A_w, b_w, cost, cost_of, rows, base)
    return Bent(bent.values, bent.step, bent.cost, bent.evaluations + 1)


def _damped_step(A: np.ndarray, b: np.ndarray, mu: float) -> np.ndarray:
    """Argmin ‖A δ + b‖² + μ·Σ d_i δ_i², d = diag(AᵀA) + 1e-12·max (Marquardt scaling)."""
    d = np.einsum("ij,ij->j", A, A)
    d = d + 1e-12 * max(float(d.max(initial=0.0)), 1e-300)
    A_aug = np.vstack([A, np.diag(np.sqrt(mu * d))])
    b_aug = np.concatenate([b, np.zeros(A.shape[1])])
    return -np.linalg.lstsq(A_aug, b_aug, rcond=None)[0]


def gauss_newton(
    problem: CalibrationProblem,
    x0: np.ndarray,
    free: np.ndarray,
    opts: GaussNewtonOptions,
    progress: Progress = None,
) -> SolverOutcome:
    """Gauss–Newton with Levenberg damping when the full step fails, then ``lm``.

    The undamped Gauss–Newton step is taken whenever it decreases the cost (so a
    well-behaved problem converges quadratically as before). When it does not, it is
    first bent to second order along the residual's curvature (``opts.acceleration``,
    :func:`pincal.identification.solvers._acceleration.bent_step`); when that fails too (or the
    trial model cannot be assembled), the step is damped,
    ``(JᵀJ + μ·diag(JᵀJ)) δ = −Jᵀr``, with μ raised ×10 per rejected and lowered ÷10 per
    accepted step until it falls below 1e-7 and pure Gauss–Newton resumes. With
    ``opts.damping`` False the full step is instead halved up to ``max_halvings`` times.
    The closed-loop solves of a :class:`CalibrationProblem` start from the first-order
    prediction of each parameter step (:attr:`CalibrationProblem.predict_starts`).
    When it stops unconverged and ``opts.fallback`` is on, :func:`levenberg_marquardt`
    re-runs from ``x0`` and its outcome is returned (the message says so).

    Args:
        problem: residual model (n parameters).
        x0: (n,) start values [SI].
        free: (p,) integer indices into the n parameters of those to fit.
        opts: options.
        progress: optional ``(iteration, cost)`` callback.

    Returns:
        SolverOutcome with :class:`LocalSolverExtras`.
    """
    if not isinstance(problem, CalibrationProblem):  # instrument models: no predictions
        out = _gauss_newton(problem, x0, free, opts, progress)
    else:
        predicting, problem.predict_starts = problem.predict_starts, True
        try:
            out = _gauss_newton(problem, x0, free, opts, progress)
        finally:
            problem.predict_starts = predicting
    if out.success or not opts.fallback:
        return out
    return _continue_with_lm(problem, x0, free, opts, progress, out)


def _continue_with_lm(
    problem: CalibrationProblem,
    x0: np.ndarray,
    free: np.ndarray,
    opts: GaussNewtonOptions,
    progress: Progress,
    gn: SolverOutcome,
) -> SolverOutcome:
    """Levenberg–Marquardt from ``x0`` after Gauss–Newton stopped unconverged (``gn``).

    The same cost: the prior of ``opts``, or its Tikhonov term ``½λ‖x − x0‖²`` as a
    prior of σ = 1/√λ about ``x0``. Its evaluation limit is 10 × ``opts.max_iterations``
    × ⌈(p + 1) / 5⌉ for p fitted parameters (at least 10 × ``max_iterations``). The outcome is
    Levenberg–Marquardt's; its iterations, history and evaluations count both runs and
    its message says what Gauss–Newton stopped at.
    """
    std = mean = None
    if opts.prior_std is not None:
        std, mean = opts.prior_std, opts.prior_mean
    elif opts.regularization > 0:
        sigma = np.full(x0.size, np.inf)
        sigma[free] = 1.0 / np.sqrt(opts.regularization)
        std, mean = tuple(sigma), tuple(float(v) for v in x0)
    # 50 iterations: 100 evaluations per parameter (the [x, z] finger's 13 needed 722)
    budget = opts.max_iterations * max(1, -(-(free.size + 1) // 5))
    lm_opts = LMOptions(max_iterations=budget, xtol=opts.xtol, loss=opts.loss,
                        f_scale=opts.f_scale, prior_std=std, prior_mean=mean)  # fmt: skip
    log.info("gauss-newton stopped (%s); re-running lm from the start", gn.message)
    on = None if progress is None else (lambda i, c: progress(gn.iterations + i, c))
    lm = levenberg_marquardt(problem, x0, free, lm_opts, on)
    assert isinstance(gn.extras, LocalSolverExtras) and isinstance(lm.extras, LocalSolverExtras)
    evals = gn.extras.evaluations + lm.extras.evaluations  # (the damping ends inside scipy)
    extras = LocalSolverExtras(evaluations=evals, rejected_steps=gn.extras.rejected_steps)
    message = (
        f"gauss-newton stopped after {gn.iterations} iterations ({gn.message}); "
        f"levenberg-marquardt from the start: {lm.message}"
    )
    return SolverOutcome(
        lm.x, gn.iterations + lm.iterations, gn.history + lm.history, lm.success, message, extras
    )


def _gauss_newton(
    problem: CalibrationProblem,
    x0: np.ndarray,
    free: np.ndarray,
    opts: GaussNewtonOptions,
    progress: Progress,
) -> SolverOutcome:
    """The body of :func:`gauss_newton` (closed-loop solves start from predictions)."""
    x = x0.copy()
    r, J, _ = problem.evaluate(x)
    evals, rejected = 1, 0
    prior = opts.prior_weights(x0.size)
    tikhonov = np.full(free.size, np.sqrt(opts.regularization))  # a prior σ = 1/√λ about x0
    wf, mean = (prior[0][free], prior[1]) if prior is not None else (tikhonov, x0)
    robust, f = opts.loss != "linear", f_scale(opts) if opts.loss != "linear" else 1.0

    def total(r: np.ndarray, values: np.ndarray) -> float:  # the data cost plus the prior's
        return robust_cost(opts.loss, r, f) + 0.5 * float(np.sum((wf * (values - mean)[free]) ** 2))

    def cost_of(values: np.ndarray) -> float:  # +inf where a trial cannot be evaluated
        if not robust:  # the model's own cost (½‖r‖²)
            return problem.cost(values) + 0.5 * float(np.sum((wf * (values - mean)[free]) ** 2))
        try:
            return total(problem.evaluate(values, jacobian=False)[0], values)
        except TRIAL_FAILURES:
            return float("inf")

    cost = total(r, x)
    history = [cost]
    message, success = "maximum iterations reached", False
    mu = 0.0
    retries = opts.acceleration or robust  # a failed full step is bent, or re-weighted
    skip, wait = 0, 1  # iterations until the full step is tried again while damped
    it = 0
    for it in range(1, opts.max_iterations + 1):
        Jf = J[:, free]
        if wf.any():
            A = np.vstack([Jf, np.diag(wf)])
            b = np.concatenate([r, wf * (x - mean)[free]])
        else:
            A, b = Jf, r
        gradient, A_d, b_d, base_d, reweighted = None, A, b, cost, None
        if robust:  # the robust cost's quadratic models (the prior's rows stay Gaussian)
            slope, curve = np.ones(b.size), np.ones(b.size)
            slope[: r.size], curve[: r.size] = loss_derivatives(opts.loss, r, f)
            # damped steps: re-weighted least squares, ½Σρ'·(b + Aδ)², which majorises
            # the robust cost (a far residual keeps curvature, so damping shortens steps)
            root = np.sqrt(slope)
            A_d, b_d = A * root[:, None], b * root
            base_d = 0.5 * float(b_d @ b_d)
            reweighted = (A_d, b_d, base_d, root[: r.size])
            # the full step: the second-order model (a far Huber residual has no curvature)
            gradient = A.T @ (slope * b)
            A, b = A * curve[:, None], b * slope / curve
        step = -np.linalg.lstsq(A, b, rcond=None)[0]
        predicted = _decrease(A, b, step, cost, gradient)
        round_off = predicted <= 1e-9 * cost  # the linear model promises only round-off
        if predicted <= 1e-12 * cost + 1e-24 * history[0]:
            message, success = "converged (predicted decrease below 1e-12 of the cost)", True
            break
        accepted, alpha, x_try = False, 1.0, x
        if mu > 0.0 and opts.damping and skip == 0:
            # damping on: the full step is still tried, and when it delivers a quarter of
            # its predicted decrease damping is off again (a damped run can crawl on loops
            # to its iteration limit); after a failed try the next waits twice as long.
            x_try = x.copy()
            x_try[free] += step
            cost_try = cost_of(x_try)
            evals += 1
            enough = cost_try < cost and cost - cost_try >= 0.25 * predicted
            if not enough and retries and not round_off:  # bent, or re-weighted
                rejected += 1  # the straight trial (a failed second one is counted below)
                bent = _second_try(problem, x, free, step, A, b, cost, cost_of, reweighted)
                evals += bent.evaluations
                if bent.values is not None:
                    x_try, step, cost_try, enough = bent.values, bent.step, bent.cost, True
            if enough:
                accepted, mu, wait = True, 0.0, 1
            else:
                rejected += 1
                wait *= 2
                skip = wait
        elif skip > 0:
            skip -= 1
        if mu == 0.0 and not accepted:
            # the full Gauss–Newton step; with damping off, a halving line search
            for _ in range(1 if opts.damping else opts.max_halvings):
                x_try = x.copy()
                x_try[free] += alpha * step
                cost_try = cost_of(x_try)
                evals += 1
                # with damping on, a full step must deliver a quarter of its predicted
                # decrease (else the linear model is not trusted and the step is damped)
                enough = not opts.damping or cost - cost_try >= 0.25 * predicted
                bend = opts.damping and retries and not round_off
                if not (cost_try < cost and enough) and bend:
                    # bent to second order along the residual's curvature (a curved valley;
                    # not at round-off, where the curvature probe is round-off too), or
                    # with a robust loss the re-weighted step
                    rejected += 1  # the straight trial (a failed second one is counted below)
                    bent = _second_try(problem, x, free, step, A, b, cost, cost_of, reweighted)
                    evals += bent.evaluations
                    if bent.values is not None:
                        x_try, step, cost_try, enough = bent.values, bent.step, bent.cost, True
                if cost_try < cost and enough:
                    accepted = True
                    break
                rejected += 1
                alpha *= 0.5
            if not accepted and at_floor(problem, cost, history[0]):
                message, success = "converged (solver precision)", True
                break
            if not accepted and opts.damping and round_off:
                # the model promises only round-off (the damped search below would say so
                # after up to 17 rejected solves): converged at the noise floor
                message = "converged (noise floor: the step promises below 1e-9 of the cost)"
                success = True
                break
            if not accepted and not opts.damping:
                message = "no decrease along the step"
                break
            if not accepted:
                mu = opts.damping_start
                log.debug("gauss-newton: full step rejected; damping μ = %g", mu)
        damped = not accepted
        if damped:
            while mu <= _MU_MAX:
                step = _damped_step(A_d, b_d, mu)
                x_try = x.copy()
                x_try[free] += step
                cost_try = cost_of(x_try)
                evals += 1
                if cost_try < cost:
                    accepted = True
                    break
                rejected += 1
                mu *= 10.0
            if not accepted:
                # no step decreases the cost although the model promised only round-off:
                # converged as well as the evaluation allows
                success = at_floor(problem, cost, history[0]) or round_off
                message = (
                    "converged (solver precision)"
                    if success
                    else f"no decrease along the step, even damped (μ up to {_MU_MAX:g})"
                )
                break
            alpha = 1.0
            # gain ratio ρ = actual / predicted decrease (Nielsen's update of μ)
            predicted_d = _decrease(A_d, b_d, step, base_d, None)
            rho = (cost - cost_try) / predicted_d if predicted_d > 0 else 0.0
            mu *= max(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0) ** 3)
            mu = mu if mu >= _MU_OFF else 0.0
        x = x_try
        small = np.linalg.norm(alpha * step) <= opts.xtol * (np.linalg.norm(x[free]) + opts.xtol)
        r, J, _ = problem.evaluate(x)
        evals += 1
        cost = total(r, x)
        history.append(cost)
        if progress:
            progress(it, cost)
        if small and not damped:
            message, success = "converged (step below tolerance)", True
            break
    extras = LocalSolverExtras(evaluations=evals, rejected_steps=rejected, damping=mu)
    return SolverOutcome(x, it, tuple(history), success, message, extras)
