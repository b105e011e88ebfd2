"""Does the linearised covariance hold at the solution? Curvature over one σ step.

The reported σ of a fit are those of its linearisation, ``cov = s²·(JᵀJ)⁻¹`` (s² the
variance factor: 1 with declared noise). They describe the fit's uncertainty only when
the model is close to linear over the confidence region. :func:`check_linearity` looks
along the principal directions of that covariance (the right singular vectors of the
whitened Jacobian of the fitted parameters, largest σ first): at ``x̂ ± k·σ_i·v_i`` it
compares

- the actual increase of the cost ½‖r‖² with the quadratic prediction ½k²s²
  (``ratio``: 1 in the linear regime; well below 1, the valley is longer or curved
  and the true interval longer than the linear one; the Bates–Watts picture of
  parameter-effects and intrinsic curvature measured directly, without second
  derivatives), and
- the change of the whitened Jacobian over the step, in the σ-scaled basis in which
  the linearised problem is orthonormal (``jacobian_change``: the spectral norm of
  ``(J(x̂ + δ) − J(x̂))·V·diag(1/s_i)``; 0 for a linear model).

The linearisation is said not to hold when, along some direction, the ratio leaves
``[1/(1+tol), 1+tol]`` or the Jacobian changes by more than ``tol`` (default 0.25) over
the step. Any object with ``evaluate(x, jacobian=True) -> (r, J, ...)`` (whitened
residuals (N,), their Jacobian (N, n)) can be checked: a pose problem
(:class:`CalibrationProblem`) or a scalar-instrument problem.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pincal.errors import PincalError
from pincal.identification.problem import ResidualModel

__all__ = [
    "TRIAL_ERRORS",
    "Curvature",
    "Linearity",
    "check_curvature",
    "check_linearity",
    "principal_directions",
]

#: what an evaluation at a trial vector may raise (the model cannot be built or solved)
TRIAL_ERRORS = (PincalError, ValueError, ArithmeticError, np.linalg.LinAlgError)
TOLERANCE = 0.25  # relative departure from the linear prediction that flags
STEP = 1.0  # the step along each direction, in σ
MAX_DIRECTIONS = 12  # directions checked, largest σ first (2 evaluations each)


@dataclass(frozen=True)
class Linearity:
    """The linearity check at a solution.

    Attributes:
        step: the step along each direction [σ].
        sigma: (d,) linearised σ along the directions checked (in the parameters' SI
            units along unit vectors).
        directions: (n_free, d) the directions checked (unit vectors over the free
            parameters), largest σ first.
        ratio: (d, 2) actual / predicted cost increase at −step and +step.
        jacobian_change: (d,) relative change of the whitened Jacobian over +step.
        tolerance: the flag threshold.
        checked: False when the check could not run (an evaluation failed).
    """

    step: float
    sigma: np.ndarray
    directions: np.ndarray
    ratio: np.ndarray
    jacobian_change: np.ndarray
    tolerance: float = TOLERANCE
    checked: bool = True

    @property
    def offending(self) -> np.ndarray:
        """Indices of the directions along which the linearisation does not hold."""
        if not self.checked or self.ratio.size == 0:
            return np.zeros(0, dtype=int)
        lo, hi = 1.0 / (1.0 + self.tolerance), 1.0 + self.tolerance
        bad_ratio = np.any((self.ratio < lo) | (self.ratio > hi) | ~np.isfinite(self.ratio), axis=1)
        bad_jac = ~(self.jacobian_change <= self.tolerance)
        return np.flatnonzero(bad_ratio | bad_jac)

    @property
    def holds(self) -> bool:
        """True when every direction checked stays within the tolerance."""
        return self.checked and self.offending.size == 0

    def worst(self) -> tuple[float, float]:
        """(ratio farthest from 1 in log scale, largest Jacobian change) over directions."""
        if self.ratio.size == 0:
            return 1.0, 0.0
        r = self.ratio[np.isfinite(self.ratio)]
        far = float(r[np.argmax(np.abs(np.log(np.clip(r, 1e-12, None))))]) if r.size else math.nan
        return far, float(np.nanmax(self.jacobian_change))

    def describe(self, names: tuple[str, ...] | None = None) -> str:
        """One sentence: where and how far the linearisation fails (empty when it holds)."""
        if self.holds:
            return ""
        if not self.checked:
            return "the linearity of the fit could not be checked (an evaluation failed)"
        bad = self.offending
        ratio, jac = self.worst()
        text = (
            f"the fit is not linear over its own confidence region: along {bad.size} of "
            f"{self.sigma.size} principal directions a {self.step:g} σ step changes the "
            f"cost by {ratio:.3g}× the linear prediction and the Jacobian by up to "
            f"{100 * jac:.0f} %"
        )
        if names is not None and len(names) == self.directions.shape[0]:
            v = self.directions[:, bad[0]]
            top = np.argsort(-np.abs(v))[:3]
            text += " (mostly " + ", ".join(names[i] for i in top if abs(v[i]) > 0.2) + ")"
        return text


def principal_directions(J: np.ndarray, scale: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Linearised σ (d,) and directions (n, d) of ``scale²·(JᵀJ)⁻¹``, largest σ first.

    Directions whose singular value is below the rank cut-off of
    :func:`pincal.identification.solvers._covariance.covariance_from_jacobian` are left out.
    """
    _, s, Vt = np.linalg.svd(np.asarray(J, dtype=float), full_matrices=False)
    n = J.shape[1]
    if s.size == 0 or not s[0] > 0:
        return np.zeros(0), np.zeros((n, 0))
    keep = s > np.sqrt(max(n, 1) * np.finfo(float).eps) * s[0]
    s, V = s[keep], Vt[keep].T
    order = np.argsort(s)  # smallest singular value = largest σ first
    return scale / s[order], V[:, order]


def check_linearity(
    problem: ResidualModel,
    x: np.ndarray,
    free: np.ndarray | None = None,
    *,
    scale: float = 1.0,
    step: float = STEP,
    tolerance: float = TOLERANCE,
    max_directions: int | None = MAX_DIRECTIONS,
) -> Linearity:
    """The linearity check at the solution ``x`` (see the module documentation).

    Args:
        problem: evaluates whitened residuals and Jacobian at a full parameter vector.
        x: (n,) the solution [SI].
        free: indices of the fitted parameters (None: all); the others stay at x.
        scale: the variance factor s (√ of the reduced χ² when the covariance was
            scaled by it; 1 with declared noise or residuals whitened by σ̂).
        step: the step along each direction [σ].
        tolerance: relative departure that flags (ratio and Jacobian change).
        max_directions: at most this many directions, largest σ first (None: all).

    Returns:
        :class:`Linearity`; ``checked`` is False when an evaluation raised or returned
        non-finite values (the caller decides; the check never raises for that).
    """
    x = np.asarray(x, dtype=float)
    idx = np.arange(x.size) if free is None else np.asarray(free, dtype=int)
    r0, J0, *_ = problem.evaluate(x, jacobian=True)
    r0, Jf = np.asarray(r0, dtype=float), np.asarray(J0, dtype=float)[:, idx]
    sigma, V = principal_directions(Jf, scale)
    if max_directions is not None:
        sigma, V = sigma[:max_directions], V[:, :max_directions]
    c0 = 0.5 * float(r0 @ r0)
    _, s_all, Vt_all = np.linalg.svd(Jf, full_matrices=False)
    keep = s_all > np.sqrt(max(idx.size, 1) * np.finfo(float).eps) * s_all[0]
    basis = Vt_all[keep].T / s_all[keep]  # σ-scaled basis: Jf @ basis is orthonormal
    ratio = np.full((sigma.size, 2), np.nan)
    change = np.full(sigma.size, np.nan)
    predicted = 0.5 * (step * scale) ** 2
    ok = True
    for i in range(sigma.size):
        for j, sign in enumerate((-1.0, 1.0)):
            xs = x.copy()
            xs[idx] += sign * step * sigma[i] * V[:, i]
            try:
                r, J, *_ = problem.evaluate(xs, jacobian=sign > 0)
            except TRIAL_ERRORS:  # a trial vector the model cannot assemble or solve
                ok = False
                continue
            r = np.asarray(r, dtype=float)
            ratio[i, j] = (0.5 * float(r @ r) - c0) / predicted
            if J is not None:
                dJ = (np.asarray(J, dtype=float)[:, idx] - Jf) @ basis
                change[i] = float(np.linalg.norm(dJ, 2))
    ok = ok and bool(np.all(np.isfinite(ratio))) and bool(np.all(np.isfinite(change)))
    return Linearity(step, sigma, V, ratio, change, tolerance, ok)


@dataclass(frozen=True)
class Curvature:
    """The second-order error of a fit over its own confidence region.

    At ``δ ~ N(0, s²(JᵀJ)⁻¹)`` the even part of the residual change,
    ``q(δ) = ½(r(x̂ + δ) + r(x̂ − δ)) − r(x̂)`` (≈ ½ δᵀ∇²r δ), moves the least-squares
    solution by ``J⁺q``: its Mahalanobis size is ``‖P_J q‖`` (P_J the projection on the
    whitened Jacobian's columns), and the fit's Mahalanobis error from the truth grows
    on average from ``k`` to ``k + E‖P_J q‖²`` (the parameter-effects curvature of
    Bates & Watts, measured over the confidence region instead of from second
    derivatives). ``excess`` is ``E‖P_J q‖² / k``: 0 for a linear model; the d²/k of
    the linearised covariance is ≈ 1 + excess. The rest of q (``intrinsic``) bends
    the model's surface and leaves the solution.

    ``second_moment`` is ``E[J⁺q (J⁺q)ᵀ]`` over the draws: the fit's error is the linear
    term ``J⁺ε`` plus ``J⁺q`` plus higher orders; the first two are uncorrelated (odd
    moments of a Gaussian vanish), so this matrix is what the second-order error adds
    to the mean squared error of x̂ on its own. It lies in the directions the curvature
    moves — the well-determined combinations A that the curved model shifts by
    quadratic terms in the weakly seen directions B — and leaves the other σ as they
    were. Not included is the cross term of the linear and the third-order error, of
    the same order in ε: relative to the σ² of A it is ~ (third derivative)·σ_B², like
    the Jacobian's change over the confidence region, while the term included grows as
    σ_B⁴/σ_A² — it dominates when σ_B ≫ σ_A (a ballbar on random poses; measured in
    ``docs/quality_gate.md``), not in a one-parameter model (for ``x + b x²`` the cross
    term is 12 b²σ⁴ against the 3 b²σ⁴ included).

    Attributes:
        excess: mean ‖P_J q‖² / k over the draws; excess_se: its standard error.
        intrinsic: mean ‖(I − P_J) q‖² / k.
        draws: δ used (evaluations: 2 each); checked: False when fewer than half the
            draws could be evaluated.
        second_moment: (k, k) ``E[J⁺q (J⁺q)ᵀ]`` over the fitted parameters, in their
            units squared (None when not checked).
        failed: draws left out because the model could not be evaluated there (a
            machine that does not assemble at x̂ ± δ): the curvature reaches beyond
            them, so the measure is then a lower bound.
    """

    excess: float
    excess_se: float
    intrinsic: float
    draws: int
    checked: bool = True
    second_moment: np.ndarray | None = None
    failed: int = 0


def check_curvature(
    problem: ResidualModel,
    x: np.ndarray,
    free: np.ndarray | None = None,
    *,
    scale: float = 1.0,
    draws: int = 8,
    seed: int = 0,
) -> Curvature:
    """The parameter-effects curvature over the confidence region (see :class:`Curvature`).

    Args:
        problem: evaluates whitened residuals (and Jacobian) at a full parameter vector.
        x: (n,) the solution [SI].
        free: indices of the fitted parameters (None: all).
        scale: the variance factor s (1 with declared noise).
        draws: δ drawn from the linearised covariance (seeded).
        seed: the seed of the draws.
    """
    x = np.asarray(x, dtype=float)
    idx = np.arange(x.size) if free is None else np.asarray(free, dtype=int)
    r0, J0, *_ = problem.evaluate(x, jacobian=True)
    r0, Jf = np.asarray(r0, dtype=float), np.asarray(J0, dtype=float)[:, idx]
    U, s, Vt = np.linalg.svd(Jf, full_matrices=False)
    keep = s > np.sqrt(max(idx.size, 1) * np.finfo(float).eps) * s[0] if s.size else s > 0
    U, s, V = U[:, keep], s[keep], Vt[keep].T
    k = max(int(s.size), 1)
    rng = np.random.default_rng(seed)
    pe: list[float] = []
    it: list[float] = []
    moment = np.zeros((s.size, s.size))
    n = max(int(draws), 1)
    for _ in range(n):
        delta = V @ (scale * rng.standard_normal(s.size) / s)
        try:
            rs = [np.asarray(problem.evaluate(x + sign * _on(idx, delta, x.size),
                                              jacobian=False)[0], dtype=float)
                  for sign in (1.0, -1.0)]  # fmt: skip
        except TRIAL_ERRORS:  # the machine does not assemble there: counted, not used
            continue
        q = 0.5 * (rs[0] + rs[1]) - r0
        if not np.all(np.isfinite(q)):
            continue
        qp = U.T @ q
        moment += np.outer(qp, qp)
        pe.append(float(qp @ qp) / (scale**2 * k))
        it.append(max(float(q @ q) - float(qp @ qp), 0.0) / (scale**2 * k))
    failed = n - len(pe)
    if len(pe) < max(2, (n + 1) // 2):
        return Curvature(math.nan, math.nan, math.nan, len(pe), False, failed=failed)
    e = np.array(pe)
    se = float(np.std(e, ddof=1) / math.sqrt(e.size))
    T = V / s  # J⁺ = V·diag(1/s)·Uᵀ
    return Curvature(float(e.mean()), se, float(np.mean(it)), int(e.size),
                     second_moment=T @ (moment / e.size) @ T.T, failed=failed)  # fmt: skip


def _on(idx: np.ndarray, delta: np.ndarray, n: int) -> np.ndarray:
    """(n,) the step ``delta`` on the parameters ``idx``, 0 elsewhere."""
    out = np.zeros(n)
    out[idx] = delta
    return out
