"""The gate of real data: held-out prediction decides, the probes describe.

With the noise estimated from the residuals (real measurements of unknown quality) the
misspecification probes test "is there structure beyond white noise?", which real
data always answer yes (joint elasticity, backlash, a capture system's distortion): a
probe's p-value is then no reason to refuse. What decides whether a calibration helps
is whether it predicts poses it did not see better than its baseline (the registration
alone for a marker table: instrument frame and marker fitted, the robot left nominal).
:func:`held_out_verdict` turns the probes' refusals into diagnostics (their size and
p-value stay in the verdict) and refuses only when cross-validation says the
calibration predicts worse than the baseline.

With declared noise (an instrument's σ known) the gate of :func:`check_quality` is
unchanged: there a probe's significance is measured against the instrument itself.

With orientation measured (a 6-D marker body) the evidence carries each block's noise
σ (:class:`BlockScales`) and the gain is that of the whitened per-pose squared error
``|Δp|²/σ_p² + θ²/σ_r²``: a calibration that predicts positions better but
orientations worse by more (each in units of its own noise) does not pass.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from pincal.identification import IdentificationResult, QualityIssue, QualityVerdict, likely_cause
from pincal.validation._cross_validation import BlockScales, CrossValidation, compare

__all__ = ["HeldOutEvidence", "held_out_verdict"]


@dataclass(frozen=True)
class HeldOutEvidence:
    """K-fold held-out errors of a calibration and of its baseline, on the same folds.

    Attributes:
        calibrated: the calibration procedure's cross-validation.
        baseline: the baseline procedure's (same folds).
        baseline_name: what the baseline is, in words (``registration only``).
        scales: each block's noise σ when orientation is measured (the gain is then
            of whitened squared errors, dimensionless), else None (positions, m²).
    """

    calibrated: CrossValidation
    baseline: CrossValidation
    baseline_name: str
    scales: BlockScales | None = None

    @property
    def whitened(self) -> bool:
        """True when the gain combines position and orientation (whitened)."""
        return self.scales is not None and self.calibrated.held_out_orientation is not None

    @property
    def gain(self) -> tuple[float, float]:
        """(baseline − calibrated held-out mean squared error, its standard error).

        [m²], or whitened (dimensionless) when :attr:`whitened`.
        """
        gain, se, _ = compare(self.calibrated, self.baseline, self.scales)
        return gain, se

    def _gain_words(self) -> str:
        gain, se = self.gain
        word = "lower" if gain >= 0 else "higher"
        if not self.whitened:
            return f"mean squared error {word} by {abs(gain) * 1e6:.3g} ± {se * 1e6:.2g} mm²"
        assert self.scales is not None
        c, b = self.calibrated.orientation_rms or 0.0, self.baseline.orientation_rms or 0.0
        return (
            f"orientation {c * 1e3:.3f} against {b * 1e3:.3f} mrad; the whitened squared "
            f"error (position / {self.scales.position * 1e3:.3g} mm, orientation / "
            f"{self.scales.orientation * 1e3:.3g} mrad) {word} by {abs(gain):.3g} ± {se:.2g}"
        )

    @property
    def ratio(self) -> float:
        """Held-out RMS of the calibration / of the baseline (< 1: the calibration helps)."""
        return self.calibrated.rms / self.baseline.rms if self.baseline.rms > 0 else float("nan")

    def describe(self) -> str:
        """One line: both held-out RMS [mm] and the gain with its standard error."""
        k = len(self.calibrated.folds)
        return (
            f"{k}-fold held-out RMS {self.calibrated.rms * 1e3:.3f} mm calibrated, "
            f"{self.baseline.rms * 1e3:.3f} mm {self.baseline_name} ({self._gain_words()})"
        )

    def to_dict(self) -> dict:
        """JSON: both procedures' held-out figures [mm], the gain and its s.e.

        [mm²]; with :attr:`whitened`, ``gain_whitened`` and its s.e. (dimensionless),
        the σ used in ``whitened_by``, and the position-only gain beside them.
        """
        gain, se, _ = compare(self.calibrated, self.baseline)
        out = {
            "folds": len(self.calibrated.folds),
            "calibrated": self.calibrated.to_dict(),
            "baseline": {"name": self.baseline_name, **self.baseline.to_dict()},
            "ratio": self.ratio,
            "gain_mse_mm2": gain * 1e6,
            "gain_standard_error_mm2": se * 1e6 if np.isfinite(se) else None,
        }
        if self.whitened:
            assert self.scales is not None
            w, wse = self.gain
            out |= {"whitened_by": self.scales.to_dict(), "gain_whitened": w,
                    "gain_whitened_standard_error": wse if np.isfinite(wse) else None}  # fmt: skip
        return out


def held_out_verdict(
    verdict: QualityVerdict, evidence: HeldOutEvidence, result: IdentificationResult
) -> QualityVerdict:
    """The verdict of a fit with estimated noise, judged by its held-out prediction.

    Probe refusals (``model``) become warnings; a calibration whose held-out mean
    squared error is not below the baseline's refuses (``held-out``); one whose gain is
    within its standard error is written with a warning. Other refusals (solver,
    parameter changes, breakdown, singular poses, units) stand.
    """
    issues = [
        replace(i, refuse=False, message=i.message + " (a diagnostic: with the noise "
                "estimated, held-out prediction decides)") if i.kind == "model" else i
        for i in verdict.issues
    ]  # fmt: skip
    gain, se = evidence.gain
    if gain <= 0:
        issues.append(QualityIssue(
            "held-out", True, f"the calibration predicts poses it did not see no better than "
            f"the {evidence.baseline_name}: {evidence.describe()}",
        ))  # fmt: skip
    elif gain <= se:
        issues.append(QualityIssue(
            "held-out", False, f"the calibration beats the {evidence.baseline_name} on "
            f"held-out poses by less than its standard error: {evidence.describe()}",
        ))  # fmt: skip
    out = replace(verdict, issues=tuple(issues), held_out=evidence.to_dict())
    if out.passed:
        return replace(out, cause="", cause_text="")
    if {i.kind for i in out.refusals} == {"held-out"}:
        return replace(out, cause="no held-out benefit", cause_text=(
            f"the data do not support calibrating the machine's geometry beyond the "
            f"{evidence.baseline_name}; more poses spread over the workspace, or a smaller "
            "preset (--params), may help."
        ))  # fmt: skip
    cause, text = likely_cause(out, result, len(evidence.calibrated.held_out))
    return replace(out, cause=cause, cause_text=text)
