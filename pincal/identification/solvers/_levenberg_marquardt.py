"""Levenberg–Marquardt: scipy's ``least_squares`` on the analytic Jacobian.

It minimises ``0.5·‖r_w(x)‖²`` (or a robust loss of the data's rows, a Gaussian prior's
rows staying least squares) over the free parameters, a trial that cannot be evaluated
being a rejected step (:mod:`pincal.identification.solvers._local`, which falls back to it).
"""

from __future__ import annotations

import numpy as np

from pincal.identification._options import LMOptions, f_scale
from pincal.identification._weighting import data_rows_loss
from pincal.identification.problem import TRIAL_FAILURES, CalibrationProblem
from pincal.identification.results import LocalSolverExtras, Progress, SolverOutcome

__all__ = ["at_floor", "levenberg_marquardt"]

FAILED_RESIDUAL = 1e100  # whitened residual entries of a trial that cannot be evaluated


def at_floor(problem: CalibrationProblem, cost: float, initial: float) -> bool:
    """True when the cost is at the kinematic solver's precision (exact data fitted)."""
    return cost <= problem.solver_floor_cost or cost <= 1e-20 * initial


_FTOL = 1e-10
"""Levenberg–Marquardt stops when an accepted step lowers the cost by less than this
share of it (scipy's ``ftol``). At the solution the cost is about ν/2, so the step left
moves the parameters by ~1e-5 σ; the TIAGo example's fit took 70 iterations at 1e-15
and 30 at 1e-10, its values equal to 7e-8 σ."""


def levenberg_marquardt(
    problem: CalibrationProblem,
    x0: np.ndarray,
    free: np.ndarray,
    opts: LMOptions,
    progress: Progress = None,
) -> SolverOutcome:
    """``scipy.optimize.least_squares`` on the free parameters.

    The residuals are whitened by the noise σ, so a robust loss' ``f_scale`` is in σ
    (:attr:`LMOptions.f_scale`). Success is scipy's convergence, or — when scipy stopped
    at its evaluation limit — a cost at the kinematic solver's precision (exact data
    fitted) or at the noise floor (a Gauss–Newton step from the end point promises less
    than 1e-9 of the cost).

    Args:
        problem: residual model (n parameters).
        x0: (n,) start values [SI].
        free: (p,) integer indices into the n parameters of those to fit.
        opts: options.
        progress: optional ``(evaluation, cost)`` callback.
    """
    history: list[float] = []
    cache: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}

    def full(z: np.ndarray) -> np.ndarray:
        x = x0.copy()
        x[free] = z
        return x

    last: list[tuple[np.ndarray, np.ndarray]] = []

    prior = opts.prior_weights(x0.size)
    wf, mean = (prior[0][free], prior[1][free]) if prior is not None else (None, None)

    def both(z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        key = z.tobytes()
        if key not in cache:
            cache.clear()
            try:
                r, J, _ = problem.evaluate(full(z))
                J = J[:, free]
                if wf is not None:  # the prior's rows
                    r = np.concatenate([r, wf * (z - mean)])
                    J = np.vstack([J, np.diag(wf)])
                last[:] = [(r, J)]
            except TRIAL_FAILURES:
                if not last:
                    raise  # the start itself cannot be evaluated
                # a trial model that cannot be assembled / solved: a huge residual makes
                # the solver reject the step and shrink its trust region
                r, J = np.full_like(last[0][0], FAILED_RESIDUAL), last[0][1]
            cache[key] = (r, J)
            history.append(0.5 * float(r @ r))
            if progress:
                progress(len(history), history[-1])
        return cache[key]

    import scipy.optimize  # here, not at import: scipy.optimize costs ~0.3 s to import

    max_nfev = opts.max_iterations * 10
    # copies: scipy < 1.14 scales the residual and Jacobian of robust losses in place
    sol = scipy.optimize.least_squares(
        lambda z: both(z)[0].copy(),
        x0[free],
        jac=lambda z: both(z)[1].copy(),
        method="lm" if opts.loss == "linear" else "trf",
        # a prior's rows stay Gaussian: the loss applies to the data's rows
        loss=opts.loss
        if wf is None or opts.loss == "linear"
        else data_rows_loss(opts.loss, problem.n_equations),
        f_scale=1.0 if opts.loss == "linear" else f_scale(opts),
        x_scale="jac",
        xtol=max(opts.xtol, 1e-15),
        ftol=_FTOL,
        gtol=1e-15,
        max_nfev=max_nfev,
    )
    x = full(sol.x)
    r_end, J_end = both(sol.x)
    cost = 0.5 * float(r_end @ r_end)
    # decrease the Gauss–Newton model still promises at the end point
    gn = np.linalg.lstsq(J_end, -r_end, rcond=None)[0]
    promised = cost - 0.5 * float(np.sum((r_end + J_end @ gn) ** 2))
    if sol.success:
        success, message = True, f"converged ({sol.message})"
    elif at_floor(problem, cost, history[0]):
        success = True
        message = (
            f"converged: cost {cost:.3g} is at the kinematic solver's precision (exact data "
            f"fitted); scipy stopped at its evaluation limit ({max_nfev}) before its own "
            "tolerances"
        )
    elif promised <= 1e-9 * cost:
        success = True
        message = (
            f"converged: cost {cost:.6g} is at the noise floor (a further Gauss–Newton step "
            f"promises {promised:.2g}); scipy stopped at its evaluation limit ({max_nfev})"
        )
    else:
        success = False
        message = (
            f"stopped at the evaluation limit ({max_nfev}) with the cost still decreasing "
            f"({cost:.6g}); raise max_iterations ({sol.message})"
        )
    extras = LocalSolverExtras(evaluations=int(sol.nfev), rejected_steps=0)
    return SolverOutcome(x, int(sol.nfev), tuple(history), success, message, extras)
