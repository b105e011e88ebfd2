"""Sensitivity-planned step identification (seed 002, the patent's iterative step planning).

The patent identifies the errors, then "plans the iteration steps" of every error
parameter from the global sensitivities (parameters of equal sensitivity are stepped
alike) until the final iteration errors are reached, and compensates by substituting
them into the constraint equations. Its formulas for the steps were lost from the seed
text (models/wedge3/README.md, "Calibration method"), so this is a reconstruction that
keeps every surviving statement and is guaranteed to reach the least-squares answer:

Each iteration linearises the whitened residual ``r(x) + J(x)·Δ`` (the cost of
:class:`pincal.identification._identify.CalibrationProblem`) and takes the planned step

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
from dataclasses import dataclass

import numpy as np

from pincal.errors import ConvergenceError, ParameterError
from pincal.identification._identify import CalibrationProblem
from pincal.measure._measurements import Measurements
from pincal.model._mechanism import Mechanism
from pincal.model._parameters import ParameterSet
from pincal.sensitivity._global import GlobalSensitivity, global_sensitivity

__all__ = ["StepPlanningResult", "step_planned_identify"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class StepPlanningResult:
    """Outcome of :func:`step_planned_identify`.

    Attributes:
        params: the parameter set (n).
        values: (n,) identified values [SI].
        steps: (iterations, n) accepted planned steps [SI].
        cost_history: 0.5·‖whitened residual‖² at the start and after each accepted step.
        iterations: accepted steps.
        converged: whether the step tolerance was reached.
        message: summary.
        sensitivity: the global sensitivity that planned the steps.
        held: names held at their initial values (insensitive).
        calibrated: mechanism with ``values`` applied (same structure as the nominal).
    """

    params: ParameterSet
    values: np.ndarray
    steps: np.ndarray
    cost_history: tuple[float, ...]
    iterations: int
    converged: bool
    message: str
    sensitivity: GlobalSensitivity
    held: tuple[str, ...]
    calibrated: Mechanism


def step_planned_identify(
    mech: Mechanism,
    params: ParameterSet,
    measurements: Measurements,
    *,
    sensitivity: GlobalSensitivity | None = None,
    workspace: np.ndarray | int = 200,
    initial: np.ndarray | None = None,
    damping: float = 1.0,
    max_iterations: int = 100,
    xtol: float = 1e-12,
) -> StepPlanningResult:
    """Identify ``params`` from measurements with sensitivity-planned steps.

    Args:
        mech: nominal mechanism.
        params: the n parameters.
        measurements: measured poses.
        sensitivity: global sensitivity of ``params`` (default: computed over
            ``workspace`` with :func:`pincal.sensitivity._global.global_sensitivity`).
        workspace: actuator rows or sample count for the default sensitivity.
        initial: (n,) start values [SI] (default nominal zeros).
        damping: initial λ (relative to the largest diagonal of JᵀJ).
        max_iterations: accepted-step limit.
        xtol: stop when ``max_i |w_i Δ_i|`` is below ``xtol·(1 + max_i |w_i x_i|)``.

    Raises:
        ParameterError: a sensitivity of other parameters, or bad settings.
    """
    if sensitivity is None:
        sensitivity = global_sensitivity(mech, params, workspace)
    if tuple(sensitivity.names) != tuple(params.names):
        raise ParameterError(
            f"sensitivity is for {list(sensitivity.names)}, parameters are {list(params.names)}"
        )
    if not damping >= 0 or int(max_iterations) < 1:
        raise ParameterError("damping must be ≥ 0 and max_iterations ≥ 1")
    problem = CalibrationProblem(mech, params, measurements)
    x = params.check_values(initial).copy()
    w_all = sensitivity.weights()
    free = np.flatnonzero(w_all > 0)
    w = w_all[free]
    held = tuple(params.names[i] for i in range(len(params)) if w_all[i] <= 0)
    r, J, _ = problem.evaluate(x)
    cost = 0.5 * float(r @ r)
    history, steps = [cost], []
    lam_rel = float(damping)
    converged, message = False, "maximum iterations reached"
    while len(steps) < int(max_iterations):
        A = J[:, free] / w  # columns per unit of w_i·Δ_i
        H = A.T @ A
        lam = lam_rel * float(np.max(np.diag(H), initial=0.0))
        g = A.T @ r
        du = -np.linalg.lstsq(H + lam * np.eye(free.size), g, rcond=None)[0]
        x_try = x.copy()
        x_try[free] += du / w
        try:
            r_try, J_try, _ = problem.evaluate(x_try)
            cost_try = 0.5 * float(r_try @ r_try)
        except ConvergenceError:
            cost_try = np.inf
        small = np.max(np.abs(du)) <= xtol * (1.0 + np.max(np.abs(w * x[free])))
        if cost_try <= cost:
            steps.append(x_try - x)
            x, r, J, cost = x_try, r_try, J_try, cost_try
            history.append(cost)
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
    return StepPlanningResult(
        params=params,
        values=x,
        steps=np.array(steps).reshape(-1, len(params)),
        cost_history=tuple(history),
        iterations=len(steps),
        converged=converged,
        message=message,
        sensitivity=sensitivity,
        held=held,
        calibrated=problem.mechanism(x),
    )
