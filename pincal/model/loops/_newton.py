"""Damped, rank-revealing Newton solve on a Pinocchio configuration manifold.

Used to close kinematic loops (forward kinematics, assembly) and to reach target poses
(inverse kinematics). Redundant closure rows and rank loss are handled by a truncated
SVD; every step is limited in norm and backtracked until the residual decreases.

Once the residual is below ``tol`` the solve is *polished*: up to ``polish_steps`` more
full Newton steps are taken while each one lowers the largest residual component. With
quadratic convergence this brings the residual from ``tol`` (1e-12) to round-off
(~1e-16), so configurations — and the measurements simulated from them — are exact to
machine precision, not only to the tolerance. That matters on ill-conditioned
identification problems, where the parameter error is the data error times the
condition number (the MJCF four-bar: 1.3e-8 from 1e-12-accurate data, ~1e-11 polished).

Over-constrained loops exported from CAD (two point closures on one axis, a planar loop
closed by a 3-D weld, numbers rounded to 7 digits) often cannot close exactly: the
redundant rows keep a residual of 1e-8..1e-7 m that no step reduces (it is orthogonal to
the range of the Jacobian). With ``redundant_tol`` > 0 such a solve is accepted as a
*least-squares closure* when the part of the residual a step can remove is below
``tol`` and what is left, the least-squares remainder, is below ``redundant_tol``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pincal.errors import ConvergenceError

__all__ = ["REDUNDANT_RTOL", "Solution", "SolverOptions", "damped_newton", "newton_step"]


@dataclass(frozen=True)
class SolverOptions:
    """Newton solver settings.

    Attributes:
        tol: convergence threshold on the largest residual component [m or rad].
        max_iterations: Newton iterations before giving up.
        max_step: largest tangent step norm per iteration [m, rad].
        rcond: relative singular-value cut-off of the rank-revealing solve.
        max_condition: condition number above which a solution is called singular.
        polish_steps: extra Newton steps after convergence, each kept only when it lowers
            the largest residual component (0: stop at ``tol``).
        max_backtracks: step halvings of the line search before an iteration is called
            stalled (the solve then fails with :class:`~pincal.errors.ConvergenceError`).
        redundant_tol: largest least-squares remainder [m or rad] accepted in redundant
            rows (see the module doc); None: set by the mechanism to
            :data:`REDUNDANT_RTOL` times its size (0 outside mechanisms: exact closure).
    """

    tol: float = 1e-12
    max_iterations: int = 60
    max_step: float = 0.5
    rcond: float = 1e-10
    max_condition: float = 1e8
    polish_steps: int = 2
    max_backtracks: int = 30
    redundant_tol: float | None = None


@dataclass(frozen=True)
class Solution:
    q: np.ndarray
    iterations: int
    residual: float
    singular_values: np.ndarray  # of the Jacobian over the free dofs at q
    jacobian: np.ndarray  # (m, k) the Jacobian over the free dofs at q
    #: largest least-squares remainder [m, rad] left in redundant rows (0: exact closure)
    remainder: float = 0.0


#: least-squares remainder accepted in redundant closure rows, relative to the size of
#: the model (its longest joint or frame offset): 1e-6 (0.5 µm on a 0.5 m machine; CAD
#: exports rounded to 7 digits leave 1e-8..1e-7 m)
REDUNDANT_RTOL = 1e-6


#: longest LU step accepted, relative to ‖r‖/‖J‖_F (a condition number bound)
_LU_CONDITION = 1e6


def newton_step(J: np.ndarray, r: np.ndarray, rcond: float) -> np.ndarray:
    """Minimum-norm least-squares solution of ``J dx = −r`` (rank-revealing).

    A square, well-conditioned J is solved by LU; anything else (redundant closure rows,
    rank loss) by a truncated SVD with relative cut-off ``rcond``. An LU step longer
    than 1e6·‖r‖/‖J‖_F shows a J conditioned worse than 1e6 (e.g. a planar loop's ``3d``
    closure in a tilted plane: three rows of rank two, none exactly zero), whose LU
    solution may be dominated by a null-space component of rounding size: the SVD
    decides then.
    """
    if J.shape[0] == J.shape[1] and J.size:
        try:
            step = -np.linalg.solve(J, r)
            r_norm = np.linalg.norm(r)
            if (
                np.all(np.isfinite(step))
                and np.linalg.norm(J @ step + r) <= 1e-8 * (r_norm + 1e-300)
                and np.linalg.norm(step) * np.linalg.norm(J) <= _LU_CONDITION * r_norm
            ):
                return step
        except np.linalg.LinAlgError:
            pass
    U, s, Vt = np.linalg.svd(J, full_matrices=False)
    if s.size == 0 or s[0] == 0.0:
        return np.zeros(J.shape[1])
    keep = s > rcond * s[0]
    coeff = (U.T @ r)[keep] / s[keep]
    return -(Vt[keep].T @ coeff)


def _polish(
    model: pin.Model,
    q: np.ndarray,
    r: np.ndarray,
    Jf: np.ndarray,
    free: np.ndarray,
    evaluate: Callable[[np.ndarray], np.ndarray],
    jacobian: Callable[[], np.ndarray],
    opt: SolverOptions,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Polish a converged solve: full Newton steps while each halves max|r|.

    Returns:
        (q, r, Jf) of the last kept iterate (at most ``opt.polish_steps`` steps).
    """
    for _ in range(opt.polish_steps):
        worst = np.max(np.abs(r), initial=0.0)
        if worst == 0.0:
            break
        dv = np.zeros(model.nv)
        dv[free] = newton_step(Jf, r, opt.rcond)
        q_try = pin.integrate(model, q, dv)
        r_try = evaluate(q_try)
        if not np.max(np.abs(r_try), initial=0.0) < 0.5 * worst:
            evaluate(q)  # leave the evaluator's state (for jacobian()) at the kept q
            break
        q, r, Jf = q_try, r_try, jacobian()[:, free]
    return q, r, Jf


def _least_squares_closed(
    model: pin.Model,
    q: np.ndarray,
    r: np.ndarray,
    Jf: np.ndarray,
    step: np.ndarray,
    free: np.ndarray,
    evaluate: Callable[[np.ndarray], np.ndarray],
    jacobian: Callable[[], np.ndarray],
    opt: SolverOptions,
) -> Solution | None:
    """The least-squares closure at q (polished), or None when q is not one.

    q is one when the residual the Newton step ``step`` removes (``Jf step``) is below
    ``opt.tol`` and the linearised remainder ``r + Jf step`` below ``opt.redundant_tol``.
    Polishing takes full steps while each halves the removable part.
    """
    removable = np.max(np.abs(Jf @ step), initial=0.0)
    remainder = np.max(np.abs(r + Jf @ step), initial=0.0)
    if removable > opt.tol or remainder > (opt.redundant_tol or 0.0):
        return None
    for _ in range(opt.polish_steps):
        if removable == 0.0:
            break
        dv = np.zeros(model.nv)
        dv[free] = step
        q_try = pin.integrate(model, q, dv)
        r_try = evaluate(q_try)
        J_try = jacobian()[:, free]
        s_try = newton_step(J_try, r_try, opt.rcond)
        m_try = np.max(np.abs(J_try @ s_try), initial=0.0)
        if not m_try < 0.5 * removable:
            evaluate(q)
            break
        q, r, Jf, step, removable = q_try, r_try, J_try, s_try, m_try
        remainder = np.max(np.abs(r + Jf @ step), initial=0.0)
    s = np.linalg.svd(Jf, compute_uv=False) if Jf.size else np.zeros(0)
    return Solution(q, 0, float(np.max(np.abs(r), initial=0.0)), s, Jf, float(remainder))


def damped_newton(
    model: pin.Model,
    q0: np.ndarray,
    free: np.ndarray,
    evaluate: Callable[[np.ndarray], np.ndarray],
    jacobian: Callable[[], np.ndarray],
    options: SolverOptions,
) -> Solution:
    """Drive ``evaluate(q)`` to zero moving only the tangent dofs ``free``.

    Args:
        model: the Pinocchio model (for ``integrate``).
        q0: (nq,) start configuration.
        free: tangent indices (k,) allowed to move.
        evaluate: residual (m,) at q; the call also prepares :func:`jacobian`.
        jacobian: (m, nv) Jacobian at the configuration last passed to ``evaluate``.
        options: tolerances and limits.

    Returns:
        The converged :class:`Solution` (singular values of the Jacobian over ``free``).

    Raises:
        ConvergenceError: no convergence within ``options.max_iterations``, or stalled.
    """
    opt = options
    q = np.array(q0, dtype=float)
    nv = model.nv
    r = evaluate(q)
    norm = np.linalg.norm(r)
    it = 0
    for it in range(opt.max_iterations + 1):
        Jf = jacobian()[:, free]
        if np.max(np.abs(r), initial=0.0) <= opt.tol:
            q, r, Jf = _polish(model, q, r, Jf, free, evaluate, jacobian, opt)
            s = np.linalg.svd(Jf, compute_uv=False) if Jf.size else np.zeros(0)
            return Solution(q, it, float(np.max(np.abs(r), initial=0.0)), s, Jf)
        if it == opt.max_iterations:
            break
        step = newton_step(Jf, r, opt.rcond)
        if opt.redundant_tol:
            done = _least_squares_closed(model, q, r, Jf, step, free, evaluate, jacobian, opt)
            if done is not None:
                return dataclasses.replace(done, iterations=it)
        step_norm = np.linalg.norm(step)
        if step_norm > opt.max_step:
            step *= opt.max_step / step_norm
        dv = np.zeros(nv)
        dv[free] = step
        alpha = 1.0
        for _ in range(opt.max_backtracks):
            q_try = pin.integrate(model, q, alpha * dv)
            r_try = evaluate(q_try)
            n_try = np.linalg.norm(r_try)
            if n_try < norm or n_try <= opt.tol:
                break
            alpha *= 0.5
        else:  # no decrease along the Newton direction: stalled
            break
        q, r, norm = q_try, r_try, n_try
    raise ConvergenceError(
        f"Newton did not converge: residual {np.max(np.abs(r)):.3e} after {it} iterations",
        residual=float(np.max(np.abs(r))),
    )
