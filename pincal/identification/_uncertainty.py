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
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from pincal.errors import PincalError
from pincal.identification._bootstrap import DRAWS, Bootstrap, bootstrap_covariance, widened
from pincal.identification._linearity import Linearity, ResidualModel, check_linearity
from pincal.identification._problem import CalibrationProblem
from pincal.identification._result import IdentificationResult
from pincal.identification._verdict import QualityIssue, QualityVerdict
from pincal.measure import Measurements, NoiseModel
from pincal.model import Mechanism

#: bootstrap σ up to (this + 3 relative standard errors of a σ from the draws) × the
#: linearised σ confirm them
CONFIRMED = 1.1

__all__ = ["UncertaintyCheck", "check_uncertainty", "pose_residual_model", "with_uncertainty"]


@dataclass(frozen=True)
class UncertaintyCheck:
    """The linearity check of a fit and, when it failed, the widened result.

    Attributes:
        result: the result with an honest covariance (the input when linear).
        linearity: the check; bootstrap: the refits (None when linear or not run).
        issue: the gate warning (None when the linearisation holds).
    """

    result: IdentificationResult
    linearity: Linearity | None
    bootstrap: Bootstrap | None = None
    issue: QualityIssue | None = None

    def to_dict(self) -> dict[str, object]:
        """JSON-ready summary (``quality.uncertainty`` of the calibration's record)."""
        lin = self.linearity
        out: dict[str, object] = {"linear": lin is None or lin.holds}
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
        return out


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
    text = lin.describe(names)
    within = CONFIRMED + 3.0 / math.sqrt(2.0 * max(boot.draws, 1))  # σ̂ s.e. ≈ σ/√(2B)
    if boot.draws >= 2 and worst <= within:
        text += (
            f"; a parametric bootstrap ({boot.draws} seeded refits) confirms the linearised "
            f"σ within its sampling error (up to {worst:.3g}×; the larger is reported)"
        )
    elif boot.draws >= 2:
        text += (
            f"; the linearised σ are too small: the σ reported are widened by a parametric "
            f"bootstrap ({boot.draws} seeded refits, up to {worst:.3g}× the linearised σ)"
        )
        if boot.failed:
            text += (
                f"; {boot.failed} of {boot.draws + boot.failed} refits did not converge: "
                "the data may not bound these parameters"
            )
    else:
        text += "; the bootstrap refits failed: the reported σ are a lower bound"
    return UncertaintyCheck(new, lin, boot, QualityIssue("linearity", False, text))


def with_uncertainty(verdict: QualityVerdict, check: UncertaintyCheck) -> QualityVerdict:
    """The verdict with the check's warning added (it never refuses)."""
    if check.issue is None:
        return verdict
    return replace(verdict, issues=(*verdict.issues, check.issue))
