"""The plain-text block of a cross-validation (printed by `pincal validate --cv K`).

Rendered from :class:`pincal.validation.CrossValidationSummary`: fit, fold-fit and
held-out RMS / max of the calibration and its baseline [mm]; with orientation measured
the same for the rotation error angle [mrad]; for a ball-in-socket calibration the
held-out seating and socket-distance errors.
"""

from __future__ import annotations

from pincal.validation import CrossValidationSummary

__all__ = ["cross_validation_text"]


#: what each baseline of a cross-validation is, in words
_BASELINES = {
    "registration only": "registration only: instrument frame + marker fitted, the robot "
    "uncalibrated",
    "nominal model": "nominal model: the model before calibration",
    "instruments only": "instruments only: the instruments' constants (pivot, centre, "
    "planes…) fitted, the machine nominal",
}


def cross_validation_text(cv: CrossValidationSummary) -> str:
    """The printed cross-validation block [mm] (a blank line first, a newline last)."""
    b = cv.baseline
    lines = [
        "",
        f"cross-validation: {cv.k} folds over {cv.poses} poses (seed {cv.seed}); "
        "every fold refitted without its poses"
        + (" (by calibrate, recorded; --refit fits them again)" if cv.recorded else ""),
        "                       fit RMS   fold fit RMS   held-out RMS   held-out max   [mm]",
        f"  calibrated model  {cv.fit_rms * 1e3:10.3f}   {cv.fold_fit_rms * 1e3:12.3f}   "
        f"{cv.held_out_rms * 1e3:12.3f}   {cv.held_out_max * 1e3:12.3f}",
        f"  {b.model[:17]:17s} {'':10s}   {b.fold_fit_rms * 1e3:12.3f}   "
        f"{b.held_out_rms * 1e3:12.3f}   {b.held_out_max * 1e3:12.3f}",
        f"  ({_BASELINES.get(b.model, b.model + ': the model before calibration')})",
    ]
    if cv.sockets:
        assert cv.socket_distance_rms is not None and cv.socket_distance_max is not None
        assert b.socket_distance_rms is not None and b.socket_distance_max is not None
        lines[2] = lines[2].replace("held-out RMS", "seating RMS ")
        lines += [
            "  held-out socket-distance error (mean predicted ball centres of each "
            "socket's held-out seatings, minus the known distance) [mm]:",
            f"  calibrated model  RMS {cv.socket_distance_rms * 1e3:.4f}   max "
            f"{cv.socket_distance_max * 1e3:.4f}",
            f"  nominal model     RMS {b.socket_distance_rms * 1e3:.4f}   max "
            f"{b.socket_distance_max * 1e3:.4f}",
        ]
    o, bo = cv.orientation, b.orientation
    if o is not None and bo is not None:
        fit = "" if o.fit_rms is None else f"{o.fit_rms * 1e3:10.3f}"
        lines += [
            "  rotation angle [mrad] fit RMS   fold fit RMS   held-out RMS   held-out max",
            f"  calibrated model  {fit:>10s}   {o.fold_fit_rms * 1e3:12.3f}   "
            f"{o.held_out_rms * 1e3:12.3f}   {o.held_out_max * 1e3:12.3f}",
            f"  {b.model[:17]:17s} {'':10s}   {bo.fold_fit_rms * 1e3:12.3f}   "
            f"{bo.held_out_rms * 1e3:12.3f}   {bo.held_out_max * 1e3:12.3f}",
        ]
    lines.append(cv.verdict)
    return "\n".join(lines) + "\n"
