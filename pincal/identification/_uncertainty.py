"""Uncertainties that hold: check the linearisation at the solution, widen when it fails.

:func:`check_uncertainty` runs :func:`pincal.identification._linearity.check_linearity`
on a fitted result; when the linearisation does not hold it replaces the result's
covariance by :func:`pincal.identification._bootstrap.widened` (each σ the larger of
the linear and the parametric-bootstrap one) and returns a gate warning that says so in
words — a covariance known to be wrong is never reported. The problem is any object
with ``evaluate(x, jacobian=True) -> (whitened r, J, ...)`` over the result's full
parameter vector; :func:`pose_residual_model` builds it for a pose fit.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from pincal.errors import PincalError
from pincal.identification._bootstrap import DRAWS, Bootstrap, bootstrap_covariance, widened
from pincal.identification._instrument_identify import InstrumentIdentification
from pincal.identification._linearity import (
    Curvature,
    Linearity,
    ResidualModel,
    check_curvature,
    check_linearity,
)
from pincal.identification._problem import CalibrationProblem
from pincal.identification._result import IdentificationResult
from pincal.identification._verdict import QualityIssue, QualityVerdict
from pincal.measure import Measurements, NoiseModel
from pincal.model import Mechanism

#: the d²/k a fit's second-order error may add before its σ are widened (instrument fits)
CURVATURE_LIMIT = 1.0
#: δ drawn by the curvature check (2 evaluations each)
CURVATURE_DRAWS = 64
#: bootstrap σ up to (this + 3 relative standard errors of a σ from the draws) × the
#: linearised σ confirm them
CONFIRMED = 1.1

__all__ = [
    "UncertaintyCheck",
    "check_uncertainty",
    "instrument_uncertainty",
    "pose_residual_model",
    "with_uncertainty",
]


@dataclass(frozen=True)
class UncertaintyCheck:
    """The linearity check of a fit and, when it failed, the widened result.

    Attributes:
        result: the result with an honest covariance (the input when linear).
        linearity: the check; bootstrap: the refits (None when linear or not run).
        issue: the gate warning (None when the linearisation holds).
        curvature: the second-order check of an instrument fit (None for pose fits).
        widened: the largest ratio, over all combinations of the fitted unknowns, of the
            reported σ to the linearised one (second-order term of an instrument fit;
            1 otherwise).
    """

    result: IdentificationResult
    linearity: Linearity | None
    bootstrap: Bootstrap | None = None
    issue: QualityIssue | None = None
    curvature: Curvature | None = None
    widened: float = 1.0

    def to_dict(self) -> dict[str, object]:
        """JSON-ready summary (``quality.uncertainty`` of the calibration's record)."""
        lin, cu = self.linearity, self.curvature
        out: dict[str, object] = {"linear": (lin is None or lin.holds) and self.issue is None}
        if cu is not None:
            out |= {"curvature_excess": _finite(cu.excess), "curvature_excess_se":
                    _finite(cu.excess_se), "curvature_draws": cu.draws,
                    "curvature_failed": cu.failed, "curvature_limit": CURVATURE_LIMIT}  # fmt: skip
        if lin is not None:
            ratio, jac = lin.worst()
            out |= {"directions_checked": int(lin.sigma.size),
                    "directions_failed": int(lin.offending.size),
                    "worst_cost_ratio": ratio if math.isfinite(ratio) else None,
                    "worst_jacobian_change": jac if math.isfinite(jac) else None,
                    "step_sigma": lin.step}  # fmt: skip
        if self.bootstrap is not None:
            b = self.bootstrap
            out |= {"method": "parametric bootstrap", "draws": b.draws, "failed": b.failed,
                    "seed": b.seed}  # fmt: skip
        elif cu is not None and cu.checked:
            out |= {"method": "second-order", "widened_max": _finite(self.widened)}
        return out


def _finite(v: float) -> float | None:
    return v if math.isfinite(v) else None


def pose_residual_model(
    result: IdentificationResult,
    mech: Mechanism,
    meas: Measurements,
    noise: NoiseModel | dict[str, float] | None = None,
) -> CalibrationProblem | None:
    """The whitened residual model the pose fit was judged with (None if it cannot be built).

    With estimated noise it is weighted by the fit's σ̂ per block.
    """
    try:
        model = CalibrationProblem(mech, result.parameter_set, meas, noise)
        if not model.known_noise:
            w = result.weighting
            if w is None:
                return None
            std = {"position": w.position_std, "orientation": w.orientation_std}
            model = model.with_block_std({b: std[b] for b in model.blocks})
    except PincalError:
        return None
    return model


def check_uncertainty(
    problem: ResidualModel,
    result: IdentificationResult,
    *,
    declared: bool = True,
    draws: int = DRAWS,
    seed: int = 0,
    progress: Callable[[int, int], None] | None = None,
) -> UncertaintyCheck:
    """Check the linearisation of ``result``; widen its covariance when it fails.

    Args:
        problem: whitened residuals over ``result.full_values`` (see module doc).
        result: the fitted result (its covariance in the order of ``identified``).
        declared: the noise was declared (variance factor 1); otherwise the covariance
            was scaled by the reduced χ².
        draws: bootstrap refits when the linearisation fails.
        seed: the seed of the bootstrap's noise draws.
        progress: ``progress(done, total)`` per bootstrap refit.
    """
    free = np.flatnonzero(result.identified)
    if free.size == 0:
        return UncertaintyCheck(result, None)
    scale = 1.0 if declared else math.sqrt(max(float(result.reduced_chi2), 0.0))
    lin = check_linearity(problem, result.full_values, free, scale=scale)
    if lin.holds:
        return UncertaintyCheck(result, lin)
    names = tuple(result.names[i] for i in free)
    boot = bootstrap_covariance(problem, result.full_values, free, scale=scale, draws=draws,
                                seed=seed, progress=progress)  # fmt: skip
    cov = widened(result.covariance, boot)
    new = replace(result, covariance=cov, std=np.sqrt(np.clip(np.diag(cov), 0.0, None)))
    worst = float(np.max(new.std / np.maximum(result.std, 1e-300)))
    text = lin.describe(names) + _bootstrap_text(boot, worst)
    return UncertaintyCheck(new, lin, boot, QualityIssue("linearity", False, text))


def instrument_uncertainty(
    fit: InstrumentIdentification,
    mech: Mechanism,
    datasets: Sequence[Any],
    labels: Sequence[str] | None = None,
    *,
    draws: int = 0,
    seed: int = 0,
    progress: Callable[[int, int], None] | None = None,
) -> UncertaintyCheck:
    """Check an instrument fit's second-order error and add it to the covariance.

    The linear σ of a ballbar or probe fit on random poses are several times too small
    in their well-determined combinations (the model bends over the confidence region
    of its weakly seen directions), while the cost-ratio check of
    :func:`check_uncertainty` fires on designed poses too, whose linear σ are right.
    Here the measure is what matters for the intervals (:func:`check_curvature`): the
    second-order error ``J⁺q`` over draws from the confidence region. Its second moment
    is added to the linearised covariance — what that error adds to the mean squared
    error of the fit about its target (see :class:`Curvature` for the term it leaves
    out), larger only in the directions the curvature moves — and
    its d²/k (``excess``) beyond :data:`CURVATURE_LIMIT` is a warning: the linearised σ
    alone would have been wrong. With ``draws`` > 0 a fit past the limit is widened by
    a parametric bootstrap of the joint fit instead (machine and instrument unknowns;
    each refit solves every pose again: minutes on a few hundred readings).

    Args:
        fit: the outcome of :func:`pincal.identification.identify_instruments`.
        mech: the nominal mechanism.
        datasets: the fit's datasets.
        labels: their labels, as given to the fit.
        draws: bootstrap refits past the limit (0: add the second-order term; e.g. 100).
        seed: the seed of the draws (curvature and bootstrap).
        progress: ``progress(done, total)`` per bootstrap refit.
    """
    from pincal.identification._instrument_problem import InstrumentProblem

    result, free = fit.result, np.asarray(fit.fitted, dtype=int)
    if free.size == 0 or result.parameter_set is None:
        return UncertaintyCheck(result, None)
    try:
        problem = InstrumentProblem(mech, result.parameter_set, datasets, labels)
    except PincalError:
        return UncertaintyCheck(result, None)
    cu = check_curvature(problem, fit.values, free, draws=CURVATURE_DRAWS, seed=seed)
    machine = free < len(result.names)
    linear = cu.checked and cu.excess <= CURVATURE_LIMIT
    drawn = cu.draws + cu.failed
    beyond = (f"{cu.failed} of {drawn} points drawn from its confidence region do not "
              "assemble (the machine does not close there)")  # fmt: skip
    if not cu.checked and draws <= 0:
        text = (f"the curvature of the fit could not be checked: {beyond}; the σ reported "
                "are the linearised ones and may be too small (a parametric bootstrap: "
                "pincal.identification.instrument_uncertainty(..., draws=100))")  # fmt: skip
        return UncertaintyCheck(result, None, None, QualityIssue("linearity", False, text), cu)
    text = (
        "the fit is not linear over its own confidence region: its second-order error "
        f"adds {cu.excess:.3g} to the d²/k of the linearised σ (0 when they are right; "
        f"limit {CURVATURE_LIMIT:g})"
        if cu.checked
        else f"the curvature of the fit could not be checked: {beyond}"
    )
    lower = f"; {beyond}: the σ may still be too small" if cu.failed else ""
    if cu.checked and (linear or draws <= 0):
        assert cu.second_moment is not None
        cov = (np.asarray(fit.covariance) + cu.second_moment)[np.ix_(machine, machine)]
        if cov.shape != np.shape(result.covariance):
            return UncertaintyCheck(result, None, curvature=cu)
        new = replace(result, covariance=cov, std=np.sqrt(np.clip(np.diag(cov), 0.0, None)))
        worst = _widest_combination(np.asarray(fit.covariance), cu.second_moment)
        if linear and not cu.failed:
            return UncertaintyCheck(new, None, curvature=cu, widened=worst)
        if linear:
            text = ("the σ reported include the fit's second-order error (it adds "
                    f"{cu.excess:.3g} to d²/k, below the limit){lower}")  # fmt: skip
            return UncertaintyCheck(new, None, None, QualityIssue("linearity", False, text),
                                    cu, worst)  # fmt: skip
        each = float(np.max(new.std / np.maximum(result.std, 1e-300), initial=1.0))
        text += (f"; the σ reported add that second-order error (its second moment over "
                 f"{cu.draws} draws from the confidence region): the σ of the combination "
                 f"it moves most is {worst:.3g}× the linearised one, the parameters' own σ "
                 f"up to {each:.2f}×{lower}; a parametric bootstrap measures them by refits "
                 "(pincal.identification.instrument_uncertainty(..., draws=100))")  # fmt: skip
        return UncertaintyCheck(new, None, None, QualityIssue("linearity", False, text), cu, worst)
    boot = bootstrap_covariance(problem, fit.values, free, draws=draws,
                                seed=seed, progress=progress)  # fmt: skip
    cov = widened(fit.covariance, boot)[np.ix_(machine, machine)]
    if cov.shape != np.shape(result.covariance):
        return UncertaintyCheck(result, None, curvature=cu)
    new = replace(result, covariance=cov, std=np.sqrt(np.clip(np.diag(cov), 0.0, None)))
    worst = float(np.max(new.std / np.maximum(result.std, 1e-300), initial=1.0))
    issue = QualityIssue("linearity", False, text + _bootstrap_text(boot, worst))
    return UncertaintyCheck(new, None, boot, issue, cu)


def _widest_combination(C: np.ndarray, M: np.ndarray) -> float:
    """Largest σ ratio over all combinations a·x of the covariance C + M to C.

    √(1 + λ_max) with λ the eigenvalues of M in the coordinates where C is the identity
    (directions C does not span left out); 1 when M vanishes.
    """
    if C.size == 0:
        return 1.0
    s, U = np.linalg.eigh(C)
    keep = s > 1e-12 * max(float(s.max()), 1e-300)
    W = U[:, keep] / np.sqrt(s[keep])
    lam = np.linalg.eigvalsh(W.T @ M @ W) if keep.any() else np.zeros(1)
    return math.sqrt(1.0 + max(float(lam[-1]), 0.0))


def _bootstrap_text(boot: Bootstrap, worst: float) -> str:
    """What the bootstrap found, after the sentence that says the fit is not linear."""
    within = CONFIRMED + 3.0 / math.sqrt(2.0 * max(boot.draws, 1))  # σ̂ s.e. ≈ σ/√(2B)
    if boot.draws >= 2 and worst <= within:
        return (
            f"; a parametric bootstrap ({boot.draws} seeded refits) confirms the linearised "
            f"σ within its sampling error (up to {worst:.3g}×; the larger is reported)"
        )
    if boot.draws < 2:
        return "; the bootstrap refits failed: the reported σ are a lower bound"
    text = (
        f"; the linearised σ are too small: the σ reported are widened by a parametric "
        f"bootstrap ({boot.draws} seeded refits, up to {worst:.3g}× the linearised σ)"
    )
    if boot.failed:
        text += (
            f"; {boot.failed} of {boot.draws + boot.failed} refits did not converge: "
            "the data may not bound these parameters"
        )
    return text


def with_uncertainty(verdict: QualityVerdict, check: UncertaintyCheck) -> QualityVerdict:
    """The verdict with the check's warning added (it never refuses)."""
    if check.issue is None:
        return verdict
    return replace(verdict, issues=(*verdict.issues, check.issue))
