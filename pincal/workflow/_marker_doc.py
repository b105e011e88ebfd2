"""The ``markers`` record of a marker calibration (manifest and identification.json).

It holds what :func:`pincal.workflow.replay_procedure` needs to run the calibration
again on other poses (set-up, preset, method, the loss used and asked, the prior used
and asked) and what a reader wants to see: the registration, the refined instrument
frame and marker(s) with 2σ [mm, mrad], the prior's cross-validation table, the
held-out evidence, the notes; the cross-validation that judged the fit, per pose
(``cross_validation``: ``validate --cv`` with the same folds and seed reuses it).
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

import pinocchio as pin

from pincal.identification import MarkerFit
from pincal.measure import marker_frame
from pincal.model import BASE_JOINT, TOOL_JOINT

if TYPE_CHECKING:
    from pincal.workflow._marker_run import MarkerRun

__all__ = ["marker_doc"]


def _mm(v: Iterable[float]) -> list[float]:
    return [float(x) * 1e3 for x in v]


def _identified(fit: MarkerFit, markers: int) -> dict[str, Any]:
    """The refined instrument frame and marker(s) [mm, mrad] with 2σ where identified."""
    res = fit.result
    joints = fit.calibrated.tree.joints
    two_sigma = dict(zip(res.identified_names, 2 * res.std, strict=True))

    def sig(prefix: str, dofs: str) -> list[float | None]:
        out = [two_sigma.get(f"{prefix}.{d}") for d in dofs.split()]
        return [None if v is None else float(v) * 1e3 for v in out]

    T = joints[BASE_JOINT].origin
    return {
        "instrument_translation_mm": _mm(T.translation),
        "instrument_rotation_rpy_mrad": _mm(pin.rpy.matrixToRpy(T.rotation)),
        "instrument_2sigma_mm_mrad": sig(BASE_JOINT, "tx ty tz rx ry rz"),
        "marker_mm": _mm(joints[TOOL_JOINT].origin.translation),
        "marker_2sigma_mm": sig(TOOL_JOINT, "tx ty tz"),
        "more_markers_mm": [
            _mm(joints[marker_frame(k)[0]].origin.translation) for k in range(1, markers)
        ],
        "more_markers_2sigma_mm": [sig(marker_frame(k)[0], "tx ty tz") for k in range(1, markers)],
    }


def _prior_table(run: MarkerRun) -> list[dict[str, float]]:
    """The prior's candidates: σ, held-out RMS [mm] (and rotation angle [mrad])."""
    c = run.choice
    rows: list[dict[str, float]] = [{"sigma": sg, "held_out_rms_mm": r} for sg, r in c.table]
    for row, angle in zip(rows, c.orientation, strict=False):
        row["held_out_orientation_rms_mrad"] = angle
    return rows


def marker_doc(run: MarkerRun) -> dict[str, Any]:
    """The ``markers`` entry of a :class:`pincal.workflow.MarkerRun` (JSON-ready)."""
    reg, prior, s = run.fit.registration, run.prior, run.settings
    return {
        **run.setup.to_dict(),
        "preset": s.preset,
        "method": s.method,
        "loss": run.loss,
        "loss_spec": s.loss,
        "prior_spec": s.prior,
        "prior": None if prior is None else {"length_mm": prior.length * 1e3,
                                             "angle_mrad": prior.angle * 1e3},
        "prior_cv": _prior_table(run) or None,
        "prior_cv_whitened_by": None if run.choice.scales is None else run.choice.scales.to_dict(),
        "cv_folds": s.folds,
        "cv_seed": s.seed,
        "cross_validation": None if run.held_out is None else {
            "folds": s.folds, "seed": s.seed,
            "calibrated": run.held_out.calibrated.to_record(),
            "baseline": run.held_out.baseline.to_record(),
        },
        "registration": {
            "rms_mm": reg.fit.rms * 1e3,
            "iterations": reg.iterations,
            "marker_mm": _mm(reg.marker),
            "more_markers_mm": [_mm(m) for m in reg.more_markers],
            "instrument_translation_mm": _mm(reg.T_instrument_base.translation),
        },
        "identified": _identified(run.fit, len(run.meas)),
        "solver": run.fit.method,
        "notes": [*run.notes, *run.warnings],
        "held_weak": list(run.fit.held_weak),
    }  # fmt: skip
