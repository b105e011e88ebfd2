"""The report's cross-validation section: held-out error beside the fit and a baseline.

Reads the ``cross_validation`` annotation, the ``cv`` object of ``pincal validate --cv K
--out`` (K-fold refits: fit RMS, held-out RMS/max [mm], and the same for the baseline —
for a marker campaign the registration-only model, the robot uncalibrated).
"""

from __future__ import annotations

import math
from typing import Any

from pincal.errors import ReportError
from pincal.report._document import Section, Table

__all__ = ["check_cross_validation", "cross_validation_section"]

_ROW_KEYS = ("fit_rms_mm", "fold_fit_rms_mm", "held_out_rms_mm", "held_out_max_mm")


def _value(doc: dict[str, Any], key: str, what: str) -> float:
    """``doc[key]`` as a finite number, NaN when absent."""
    v = doc.get(key)
    if v is None:
        return float("nan")
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise ReportError(f"'{what}.{key}' must be a finite number [mm], got {v!r}")
    return float(v)


def check_cross_validation(cv: object) -> None:
    """Check the annotation (ReportError naming the entry when it is malformed)."""
    if not isinstance(cv, dict):
        raise ReportError("'cross_validation' must be the 'cv' object of `pincal validate --cv`")
    for key in ("k", "poses"):
        if not isinstance(cv.get(key), int) or isinstance(cv.get(key), bool):
            raise ReportError(f"'cross_validation.{key}' must be an integer")
    if not math.isfinite(_value(cv, "held_out_rms_mm", "cross_validation")):
        raise ReportError("'cross_validation.held_out_rms_mm' is missing")
    for key in _ROW_KEYS:
        _value(cv, key, "cross_validation")
    base = cv.get("baseline")
    if base is not None:
        if not isinstance(base, dict):
            raise ReportError("'cross_validation.baseline' must be an object")
        for key in _ROW_KEYS:
            _value(base, key, "cross_validation.baseline")


def _mm(v: float) -> float | str:
    """A value [mm] to 1 µm, or "–" when the validation did not compute it."""
    return round(v, 3) if math.isfinite(v) else "–"


def cross_validation_section(cv: dict[str, Any]) -> Section:
    """Held-out RMS/max beside the fit RMS, for the calibration and its baseline [mm]."""
    rows = [["calibrated model", *(_mm(_value(cv, k, "cv")) for k in _ROW_KEYS)]]
    base = cv.get("baseline")
    if isinstance(base, dict):
        name = str(base.get("model", "baseline"))
        rows.append([name, *(_mm(_value(base, k, "baseline")) for k in _ROW_KEYS)])
    seed = f", seed {cv['seed']}" if isinstance(cv.get("seed"), int) else ""
    text = (
        f"{cv['k']}-fold cross-validation over {cv['poses']} poses{seed}: every fold is "
        "refitted from scratch without its poses and predicts them. Fit RMS: the fit on "
        "all poses; fold fit RMS: the folds' own fits; held-out RMS / max: the poses no fit "
        "saw, position error in mm."
    )
    if isinstance(base, dict) and base.get("model") == "registration only":
        text += (
            " Registration only fits the instrument frame and the marker with the robot "
            "uncalibrated: the baseline a calibration must beat."
        )
    verdict = cv.get("verdict")
    if isinstance(verdict, str) and verdict:
        text += f"\n\nVerdict: {verdict}."
    table = Table(
        ["model", "fit RMS [mm]", "fold fit RMS [mm]", "held-out RMS [mm]", "held-out max [mm]"],
        rows,
    )
    return Section("Cross-validation", text, (), (table,))
