"""Sensitivity-planned step identification (seed 002, the patent's iterative step planning).

The patent identifies the errors, then "plans the iteration steps" of every error
parameter from the global sensitivities (parameters of equal sensitivity are stepped
alike) until the final iteration errors are reached, and compensates by substituting
them into the constraint equations. Its formulas for the steps were lost from the seed
text (models/wedge3/README.md, "Calibration method"), so this is a reconstruction that
keeps every surviving statement and is guaranteed to reach the least-squares answer:

Each iteration linearises the whitened residual ``r(x) + J(x)·Δ`` (the cost of
:class:`pincal.identification.CalibrationProblem`) and takes the planned step

    Δ = argmin ‖r + J Δ‖² + λ Σ_i (w_i Δ_i)²,

with ``w_i`` the normalised global sensitivity of parameter i
(:meth:`pincal.sensitivity._global.GlobalSensitivity.weights`, 0 < w ≤ 1): the step of a
parameter is planned in units of its workspace-averaged effect, so highly sensitive
parameters take small steps and weakly sensitive ones large steps, and parameters of
equal global sensitivity are planned identically. λ starts at ``damping`` and is divided
by 10 after an accepted step (multiplied by 10 after a rejected one), so the iteration
ends as Gauss–Newton and converges to the same fixed point (the least-squares solution;
on noise-free data the true errors). Insensitive parameters (zero global sensitivity)
are held at their initial values.
"""

from __future__ import annotations

import logging

import numpy as np

from pincal.errors import ParameterError
from pincal.identification._options import StepPlanningOptions
from pincal.identification.problem import CalibrationProblem
from pincal.identification.results import Progress, SolverOutcome, StepPlanningExtras
from pincal.sensitivity import global_sensitivity

__all__ = ["step_planning"]

log = logging.getLogger(__name__)


def step_planning(
    problem: CalibrationProblem,
    x0: np.ndarray,
    free: np.ndarray,
    opts: StepPlanningOptions,
    progress: Progress = None,
) -> SolverOutcome:
    """Identify the free parameters of ``problem`` with sensitivity-planned steps.

    Args:
        problem: residual model (n parameters).
        x0: (n,) start values [SI].
        free: indices of the parameters to fit (k,) (the insensitive ones among
            them are held too).
        opts: :class:`StepPlanningOptions`.
        progress: optional ``progress(step, cost)`` callback, called with the step
            number and the cost ½‖r‖² after each step, or None.

    Returns:
        SolverOutcome with :class:`StepPlanningExtras`; ``fitted`` lists the parameters
        actually stepped.

    Raises:
        ParameterError: the options' sensitivity is of other parameters.
    """
    mech, params = problem.mech, problem.params
    sensitivity = opts.sensitivity
    if sensitivity is None:
        sensitivity = global_sensitivity(mech, params, opts.workspace)
    if tuple(sensitivity.names) != tuple(params.names):
        raise ParameterError(
            f"sensitivity is for {list(sensitivity.names)}, parameters are {list(params.names)}"
        )
    x = np.asarray(x0, dtype=float).copy()
    w_all = np.asarray(sensitivity.weights(), dtype=float)
    free = np.asarray([i for i in free if w_all[i] > 0], dtype=int)
    w = w_all[free]
    r, J, _ = problem.evaluate(x)
    cost = 0.5 * float(r @ r)
    history: list[float] = [cost]
    steps: list[np.ndarray] = []
    lam_rel = float(opts.damping)
    converged, message = False, "maximum iterations reached"
    while len(steps) < int(opts.max_iterations) and free.size:
        A = J[:, free] / w  # columns per unit of w_i·Δ_i
        H = A.T @ A
        lam = lam_rel * float(np.max(np.diag(H), initial=0.0))
        g = A.T @ r
        du = -np.linalg.lstsq(H + lam * np.eye(free.size), g, rcond=None)[0]
        x_try = x.copy()
        x_try[free] += du / w
        cost_try = problem.cost(x_try)
        if np.isfinite(cost_try) and cost_try <= cost:
            r_try, J_try, _ = problem.evaluate(x_try)
        small = np.max(np.abs(du)) <= opts.xtol * (1.0 + np.max(np.abs(w * x[free])))
        if cost_try <= cost:
            steps.append(x_try - x)
            x, r, J, cost = x_try, r_try, J_try, cost_try
            history.append(cost)
            if progress:
                progress(len(steps), cost)
            lam_rel /= 10.0
            if small:
                converged, message = True, "converged (planned step below tolerance)"
                break
        else:
            if small or lam_rel > 1e12:
                converged = small
                message = "converged (no further decrease)" if small else "step rejected"
                break
            lam_rel = max(lam_rel, 1e-12) * 10.0
    log.info("step planning: %s after %d steps, cost %.6g", message, len(steps), cost)
    extras = StepPlanningExtras(
        steps=np.array(steps).reshape(-1, len(params)), weights=w_all, sensitivity=sensitivity
    )
    return SolverOutcome(x, len(steps), tuple(history), converged, message, extras, fitted=free)
