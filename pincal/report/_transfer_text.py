"""The printed transfer of a marker calibration to another session (``validate --data``)."""

from __future__ import annotations

from pincal.validation import HeldOutEvidence

__all__ = ["transfer_text"]


def transfer_text(evidence: HeldOutEvidence, data: str) -> str:
    """The block [mm] (a blank line first, a newline last)."""
    cal, base = evidence.calibrated, evidence.baseline
    k = len(cal.folds)
    gain, se = evidence.gain
    verdict = (
        "the calibrated geometry carries over to this session"
        if gain > se
        else "the calibrated geometry does NOT beat the nominal one on this session by more "
        "than the standard error"
    )
    lines = [
        "",
        f"transfer to {data}: the instrument frame and marker(s) registered again on it "
        f"({k}-fold: registered on {k - 1} folds, predicting the last), the robot as "
        "calibrated and as nominal (registration only)",
        "                        held-out RMS   held-out max   [mm]",
        f"  calibrated robot    {cal.rms * 1e3:12.3f}   {cal.max * 1e3:12.3f}",
        f"  registration only   {base.rms * 1e3:12.3f}   {base.max * 1e3:12.3f}",
        f"ratio calibrated / registration only {evidence.ratio:.3f}; mean squared error "
        f"{'lower' if gain >= 0 else 'higher'} by {abs(gain) * 1e6:.3g} ± {se * 1e6:.2g} mm²: "
        f"{verdict}",
    ]
    return "\n".join(lines) + "\n"
