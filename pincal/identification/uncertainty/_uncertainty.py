"""Uncertainties that hold: the linear covariance, checked, and a bootstrap on request.

:func:`check_uncertainty` runs :func:`pincal.identification.uncertainty._linearity.check_linearity`
on a fitted result. The covariance it returns is always the linear one — the SVD of the
whitened Jacobian at the solution, ``s²(JᵀJ)⁻¹`` — and, where the check finds the fit
not linear along some principal directions, that covariance inflated along exactly
those directions by the measured spread (:func:`inflated_covariance`) plus the measured
second-order term (:func:`check_curvature`; method ``inflated``), with a gate warning
that says so in words. No written covariance is a sample covariance of refits: a
parametric bootstrap (:func:`bootstrap_covariance`) runs only when asked for
(``bootstrap=N``) and is reported beside the linear σ (``to_dict()["bootstrap"]``).

The problem is any object with ``evaluate(x, jacobian=True) -> (whitened r, J, ...)``
over the result's full parameter vector; :func:`pose_residual_model` builds it for a
pose fit and :func:`pose_recipe` what rebuilds it in a worker process.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from pincal.errors import PincalError
from pincal.identification._verdict import QualityIssue, QualityVerdict
from pincal.identification.problem import (
    CalibrationProblem,
    PoseRecipe,
    ResidualModel,
    mechanism_blob,
)
from pincal.identification.results import IdentificationResult
from pincal.identification.uncertainty._bootstrap import Bootstrap, bootstrap_covariance
from pincal.identification.uncertainty._inflation import (
    Inflation,
    inflated_covariance,
    widest_combination,
)
from pincal.identification.uncertainty._intervals import Intervals, interval_quantiles
from pincal.identification.uncertainty._linearity import (
    Curvature,
    Linearity,
    check_curvature,
    check_linearity,
)
from pincal.measure import Measurements, NoiseModel
from pincal.model import Mechanism

#: the d²/k a fit's second-order error may add before it is a warning (instrument fits)
CURVATURE_LIMIT = 1.0
#: δ drawn by the curvature check (2 evaluations each)
CURVATURE_DRAWS = 64

#: ``method`` of a check: how the written covariance was made (a noun phrase without
#: its article, as :data:`KINDS` and the texts that print them expect)
METHODS = {
    "linear": "linear covariance s²(JᵀWJ)⁻¹ at the solution",
    "inflated": "linear covariance, inflated along the principal directions the "
                "linearity check finds non-linear (each by its measured spread), plus the "
                "second moment of the fit's second-order error over its confidence region",
    "second-order": "linear covariance plus the second moment of the fit's "
                    "second-order error over its confidence region",
}  # fmt: skip

#: what a written covariance is called, by :func:`covariance_kind`
KINDS = {
    "cramer-rao": "Cramér–Rao bound (Jᵀ Σ⁻¹ J)⁻¹ at the solution for the declared noise",
    "linear": "linear covariance s²(JᵀWJ)⁻¹ at the solution, with the noise estimated from "
              "the residuals (not a Cramér–Rao bound: the noise is not known)",
    "inflated": METHODS["inflated"],
    "second-order": METHODS["second-order"],
    "bootstrap-widened": "linear σ widened by a parametric bootstrap (written by an older "
                         "pincal: its inverse is not a covariance to rely on)",
}  # fmt: skip

__all__ = [
    "CURVATURE_DRAWS",
    "CURVATURE_LIMIT",
    "KINDS",
    "METHODS",
    "UncertaintyCheck",
    "check_uncertainty",
    "covariance_kind",
    "pose_recipe",
    "pose_residual_model",
    "prediction_covariance",
    "with_uncertainty",
]


@dataclass(frozen=True)
class UncertaintyCheck:
    """The linearity check of a fit, the covariance written, a bootstrap beside it.

    Attributes:
        result: the result with the covariance written (the input when linear).
        linearity: the check (None when not run: an instrument fit, nothing fitted).
        bootstrap: the refits run on request (None without ``bootstrap=N``); reported
            beside the written σ, never written.
        issue: the gate warning (None when the linearisation holds).
        curvature: the second-order check of an instrument fit (None for pose fits).
        widened: the largest ratio, over all combinations of the fitted unknowns, of the
            written σ to the linear one (inflation or second-order term; 1 otherwise).
        method: how the written covariance was made (a key of :data:`METHODS`).
        linear_std: (k,) the linear σ of the identified parameters [SI].
        inflation: the per-direction inflation (None when not inflated).
        intervals: the quantiles of the intervals and joint region (None: not computed).
        linear_covariance: (k, k) the linear covariance of the identified parameters
            [SI] when the one written is widened (``method`` not ``linear``), else None;
            recorded as ``linear_covariance`` (:func:`prediction_covariance`).
    """

    result: IdentificationResult
    linearity: Linearity | None
    bootstrap: Bootstrap | None = None
    issue: QualityIssue | None = None
    curvature: Curvature | None = None
    widened: float = 1.0
    method: str = "linear"
    linear_std: np.ndarray | None = None
    inflation: Inflation | None = None
    intervals: Intervals | None = None
    linear_covariance: np.ndarray | None = None

    def to_dict(self) -> dict[str, object]:
        """JSON-ready summary (``quality.uncertainty`` of the calibration's record)."""
        lin, cu = self.linearity, self.curvature
        out: dict[str, object] = {"linear": (lin is None or lin.holds) and self.issue is None,
                                  "method": self.method}  # fmt: skip
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
        if self.inflation is not None:
            out |= {"directions_inflated": int(self.inflation.inflated.size),
                    "directions_unmeasured": int(self.inflation.unmeasured.size)}  # fmt: skip
        if self.method != "linear":
            out["widened_max"] = _finite(self.widened)
            if self.linear_covariance is not None:
                out["linear_covariance"] = np.asarray(self.linear_covariance).tolist()
        if self.intervals is not None:
            out["intervals"] = self.intervals.to_dict()
        if self.bootstrap is not None:
            out["bootstrap"] = self.bootstrap_dict()
        return out

    def bootstrap_dict(self) -> dict[str, object]:
        """The bootstrap beside the written σ: per-parameter σ [SI] of both, by name."""
        b = self.bootstrap
        if b is None:
            return {}
        names = tuple(np.asarray(self.result.names)[np.asarray(self.result.identified)])
        lin = self.linear_std if self.linear_std is not None else self.result.std
        sb = b.std
        ok = b.draws >= 2 and sb.shape == lin.shape
        ratio = sb / np.maximum(lin, 1e-300) if ok else np.full(len(names), np.nan)
        return {"draws": b.draws, "failed": b.failed, "seed": b.seed,
                "std": {n: _finite(float(v)) for n, v in zip(names, sb, strict=False)},
                "linear_std": {n: float(v) for n, v in zip(names, lin, strict=False)},
                "largest_ratio": _finite(float(np.max(ratio))) if ok and ratio.size else None,
                "written": False}  # fmt: skip


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
            std = _block_std(result, model)
            if std is None:
                return None
            model = model.with_block_std(std)
    except PincalError:
        return None
    return model


def _block_std(result: IdentificationResult, model: CalibrationProblem) -> dict[str, float] | None:
    w = result.weighting
    if w is None:
        return None
    std = {"position": w.position_std, "orientation": w.orientation_std}
    return {b: std[b] for b in model.blocks}


def pose_recipe(
    result: IdentificationResult,
    mech: Mechanism,
    meas: Measurements,
    noise: NoiseModel | dict[str, float] | None = None,
) -> PoseRecipe | None:
    """What rebuilds :func:`pose_residual_model` in a worker process (None if it cannot)."""
    model = pose_residual_model(result, mech, meas, noise)
    if model is None or result.parameter_set is None:
        return None
    std = None if model.noise_source != "estimated" else _block_std(result, model)
    try:
        return PoseRecipe(mechanism_blob(mech), result.parameter_set, meas, noise, std)
    except (AttributeError, TypeError):  # a mechanism without a recipe: refit in the caller
        return None


def result_intervals(result: IdentificationResult, declared: bool) -> Intervals:
    """The quantiles of ``result``'s intervals (Student-t / F when its noise is estimated)."""
    w = getattr(result, "weighting", None)
    redundancy = None if w is None else w.redundancy
    return interval_quantiles(int(np.sum(result.identified)), redundancy, estimated=not declared)


def check_uncertainty(
    problem: ResidualModel,
    result: IdentificationResult,
    *,
    declared: bool = True,
    bootstrap: int = 0,
    seed: int = 0,
    progress: Callable[[int, int], None] | None = None,
    n_jobs: int = 1,
    factory: Callable[[], ResidualModel] | None = None,
) -> UncertaintyCheck:
    """Check the linearisation of ``result``; inflate along the directions where it fails.

    Args:
        problem: whitened residuals over ``result.full_values`` (see module doc).
        result: the fitted result (its covariance in the order of ``identified``).
        declared: the noise was declared (variance factor 1); otherwise the covariance
            was scaled by the reduced χ² and the intervals use Student-t / F quantiles.
        bootstrap: parametric-bootstrap refits to report beside the σ (0: none run).
        seed: the seed of the bootstrap's noise draws.
        progress: ``progress(done, total)`` per bootstrap refit.
        n_jobs: bootstrap worker processes (joblib; -1 = every CPU; needs ``factory``).
        factory: picklable, rebuilds ``problem`` in a worker (:func:`pose_recipe`).
    """
    free = np.flatnonzero(result.identified)
    if free.size == 0:
        return UncertaintyCheck(result, None)
    intervals = result_intervals(result, declared)
    scale = 1.0 if declared else math.sqrt(max(float(result.reduced_chi2), 0.0))
    boot = None
    if bootstrap:
        boot = bootstrap_covariance(problem, result.full_values, free, scale=scale,
                                    draws=bootstrap, seed=seed, progress=progress,
                                    n_jobs=n_jobs, factory=factory)  # fmt: skip
    lin = check_linearity(problem, result.full_values, free, scale=scale)
    base = UncertaintyCheck(result, lin, boot, linear_std=result.std, intervals=intervals)
    if lin.holds:
        return base
    names = tuple(result.names[i] for i in free)
    inf = inflated_covariance(result.covariance, lin)
    text = lin.describe(names)
    if not lin.checked:
        return replace(base, issue=QualityIssue("linearity", False, text + (
            "; the σ reported are the linear ones and may be too small")))
    cu = check_curvature(problem, result.full_values, free, scale=scale,
                         draws=CURVATURE_DRAWS, seed=seed)  # fmt: skip
    C = np.asarray(result.covariance, dtype=float)
    cov = inf.covariance + (cu.second_moment if cu.second_moment is not None else 0.0)
    new = replace(result, covariance=cov, std=np.sqrt(np.clip(np.diag(cov), 0.0, None)))
    worst = widest_combination(C, cov - C)
    text += ((f"; the covariance reported is the linear one inflated along the "
              f"{inf.inflated.size} directions whose cost rises less than predicted (each σ "
              "by 1/√(measured rise / predicted)), every other direction as the "
              "linearisation gives it")
             if inf.inflated.size else
             "; the covariance reported is the linear one (along no direction does the cost "
             "rise less than predicted)")  # fmt: skip
    text += (", plus the second moment of the fit's second-order error over "
             f"{cu.draws} draws from its confidence region (it adds {cu.excess:.2g} to d²/k); "
             f"the combination it moves most has {worst:.3g}× the linear σ")  # fmt: skip
    if inf.unmeasured.size or cu.failed or not cu.checked:
        text += ("; along some directions the cost did not rise or the model could not be "
                 "evaluated: the σ there are a lower bound")  # fmt: skip
    if boot is not None:
        text += _bootstrap_text(boot, result.std)
    return replace(base, result=new, issue=QualityIssue("linearity", False, text),
                   widened=worst, method="inflated", inflation=inf, curvature=cu,
                   linear_covariance=C)  # fmt: skip


def _bootstrap_text(boot: Bootstrap, linear_std: np.ndarray) -> str:
    """What the bootstrap found, beside the linear σ (it never replaces them)."""
    if boot.draws < 2:
        return "; the bootstrap refits failed"
    ratio = boot.std / np.maximum(linear_std, 1e-300)
    text = (f"; a parametric bootstrap ({boot.draws} seeded refits, reported beside, not "
            f"written) gives σ from {np.min(ratio):.3g}× to {np.max(ratio):.3g}× the linear ones "
            f"(its sampling error ≈ {100 / math.sqrt(2 * boot.draws):.0f} % of a σ)")  # fmt: skip
    if boot.failed:
        text += (f"; {boot.failed} of {boot.draws + boot.failed} refits did not converge: "
                 "the data may not bound these parameters")  # fmt: skip
    return text


def covariance_kind(annotations: Mapping[str, Any], noise_source: str | None) -> str:
    """Which covariance a calibration wrote: a key of :data:`KINDS`.

    ``cramer-rao`` only for the linear covariance at a declared noise.

    Args:
        annotations: the record's annotations (``quality.uncertainty.method``).
        noise_source: its weighting's source (``declared``, ``per-pose``, ``estimated``).
    """
    quality = annotations.get("quality")
    unc = quality.get("uncertainty") if isinstance(quality, Mapping) else None
    unc = unc if isinstance(unc, Mapping) else {}
    method = unc.get("method")
    if method is None and unc.get("draws"):  # an older pincal's bootstrap widening
        return "bootstrap-widened"
    if method in ("inflated", "second-order"):
        return str(method)
    return "cramer-rao" if noise_source in ("declared", "per-pose") else "linear"


def prediction_covariance(
    annotations: Mapping[str, Any], covariance: np.ndarray, noise_source: str | None
) -> tuple[np.ndarray, str]:
    """The covariance a prediction of the calibrated model's outputs propagates, and its kind.

    The linear one (``s²(JᵀWJ)⁻¹`` at the solution; the Cramér–Rao bound at a declared
    noise) when the written covariance was widened for the parameters' curvature
    (``quality.uncertainty.linear_covariance``), else the written one. The widening
    (inflation, second-order term) is the parameter-effects curvature: the fit moves
    along the valley of the curved model, so its parameters err more than the linear σ
    say, but the model's outputs along that valley do not change, to second order: the
    fitted values' error is ``P_J ε`` plus the intrinsic curvature only. Propagating
    the widened covariance through the Jacobian counts the valley as output error (on
    the RUSR with a universal joint 0.81 mm predicted against 0.019 mm achieved).

    Args:
        annotations: the record's annotations.
        covariance: (k, k) the written covariance of the identified parameters [SI].
        noise_source: its weighting's source (``declared``, ``per-pose``, ``estimated``).

    Returns:
        ((k, k) covariance [SI], its kind: a key of :data:`KINDS`).
    """
    written = np.asarray(covariance, dtype=float)
    quality = annotations.get("quality")
    unc = quality.get("uncertainty") if isinstance(quality, Mapping) else None
    lin = unc.get("linear_covariance") if isinstance(unc, Mapping) else None
    if lin is not None:
        cov = np.asarray(lin, dtype=float)
        if cov.shape == written.shape:
            return cov, covariance_kind({}, noise_source)  # the linear one, by its noise
    return written, covariance_kind(annotations, noise_source)


def with_uncertainty(verdict: QualityVerdict, check: UncertaintyCheck) -> QualityVerdict:
    """The verdict with the check's warning added (it never refuses)."""
    if check.issue is None:
        return verdict
    return replace(verdict, issues=(*verdict.issues, check.issue))
