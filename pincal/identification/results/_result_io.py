"""``identification.json``: its format and the one writer of an identification record.

Format version 2 (pincal ≥ 0.2), SI values::

    {"format": "pincal identification", "version": 2, "units": "SI (m, rad)",
     "model", "preset", "method", "success", "message", "iterations", "reduced_chi2",
     "equations", "poses", "names" (all n, in order),
     "components": [...]  # measured components of the residual columns, e.g. x y rz
     "parameters": [{"name", "unit", "value", "std", "initial"[, "true"]}],  # identified
     "held": [{"name", "unit", "value"[, "true"]}],                         # not identified
     "covariance": [[...]],                  # (k, k) of the identified parameters
     "cost_history": [...],
     "residuals": {"before": {...mm/mrad}, "after": {...}, "per_pose_SI": [[...]],
                   "per_pose_before_SI": [[...]]},
     "identifiability": {"parameters", "rank", "unidentifiable", "explanation"},
     "extras": {"type": "local" | "qpso" | "step-planned", ...},
     "weighting": {"source": "declared" | "per-pose" | "estimated", "position_std" [m],
                   "orientation_std" [rad], "rounds", "converged", "redundancy", "loss",
                   "f_scale", "pose_weights", "downweighted", "outliers", "whitened"},
     ...annotations (validation_before/after, validation_errors, index_history, data, ...)}

:func:`result_to_dict` (here) writes it from a record or a live result;
:func:`pincal.identification.result_from_dict` (:mod:`._result_read`) reads it back as an
:class:`IdentificationRecord`. Files without ``version`` (pincal 0.1) are refused.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from pincal.errors import ReportError
from pincal.identification.results._result import (
    IdentifiabilitySummary,
    IdentificationRecord,
    LocalSolverExtras,
    QPSOExtras,
    ResidualStats,
    SolverExtras,
    StepPlanningExtras,
)

__all__ = ["FORMAT_NAME", "FORMAT_VERSION", "OWNED", "STATS", "result_to_dict"]

FORMAT_NAME = "pincal identification"
FORMAT_VERSION = 2
OWNED = {
    "format",
    "version",
    "units",
    "model",
    "preset",
    "method",
    "success",
    "message",
    "iterations",
    "reduced_chi2",
    "equations",
    "poses",
    "components",
    "names",
    "parameters",
    "held",
    "covariance",
    "cost_history",
    "residuals",
    "identifiability",
    "extras",
    "weighting",
}
STATS = (
    ("rms_position_mm", "rms_position", 1e3),
    ("max_position_mm", "max_position", 1e3),
    ("rms_orientation_mrad", "rms_orientation", 1e3),
    ("max_orientation_mrad", "max_orientation", 1e3),
)


def _json_float(v: float) -> float | None:
    return None if not math.isfinite(float(v)) else float(v)


def _stats_dict(s: ResidualStats) -> dict[str, float | None]:
    out = {}
    for key, attr, f in STATS:
        v = getattr(s, attr)
        out[key] = None if math.isnan(v) else v * f
    return out


def _extras_dict(e: SolverExtras | None) -> dict[str, Any] | None:
    if isinstance(e, LocalSolverExtras):
        return {
            "type": "local",
            "evaluations": e.evaluations,
            "rejected_steps": e.rejected_steps,
            "damping": _json_float(e.damping),
        }
    if isinstance(e, QPSOExtras):
        return {
            "type": "qpso",
            "cost": _json_float(e.cost),
            "initial_cost": _json_float(e.initial_cost),
            "nfev": e.nfev,
            "order": list(e.order),
            "seconds": e.seconds,
            "swarm_history": [_json_float(v) for v in e.swarm_history],
        }
    if isinstance(e, StepPlanningExtras):
        return {
            "type": "step-planned",
            "steps": np.asarray(e.steps).tolist(),
            "weights": np.asarray(e.weights).tolist(),
        }
    return None


def _identifiability_dict(s: IdentifiabilitySummary) -> dict[str, Any]:
    out: dict[str, Any] = {
        "parameters": s.parameters,
        "rank": s.rank,
        "unidentifiable": list(s.unidentifiable),
        "explanation": list(s.explanation),
    }
    if s.breaks_closure:  # every name (the explanation groups them in one line)
        out["breaks_closure"] = list(s.breaks_closure)
    return out


def result_to_dict(
    result: IdentificationRecord, annotations: Mapping[str, Any] | None = None
) -> dict[str, Any]:
    """The JSON document of ``result`` (format version 2, SI values).

    Args:
        result: the identification (a live :class:`IdentificationResult` or a record
            read back: both give the same document).
        annotations: JSON-ready context added at the top level (merged over
            ``result.annotations``). The key ``truth`` ({name: value [SI]}) is written as
            ``true`` in the parameter entries.

    Raises:
        ReportError: an annotation would overwrite a key of the result.
    """
    notes = {} if result.joint is None else result.joint.to_dict()
    notes.update(result.annotations)
    notes.update(annotations or {})
    clash = sorted(set(notes) & OWNED)
    if clash:
        raise ReportError(f"annotations {clash} would overwrite result entries; rename them")
    truth = notes.pop("truth", None) or {}
    entries: list[dict[str, Any]] = []
    held: list[dict[str, Any]] = []
    std = iter(result.std)
    for k, name in enumerate(result.names):
        e: dict[str, Any] = {
            "name": name,
            "unit": result.units[k],
            "value": float(result.full_values[k]),
        }
        if result.identified[k]:
            e["std"] = float(next(std))
            e["initial"] = float(result.initial_values[k])
        if name in truth:
            e["true"] = float(truth[name])
        (entries if result.identified[k] else held).append(e)
    doc: dict[str, Any] = {
        "format": FORMAT_NAME,
        "version": FORMAT_VERSION,
        "units": "SI (m, rad)",
        "model": result.model,
        "preset": result.preset,
        "method": result.method,
        "success": bool(result.success),
        "message": result.message,
        "iterations": int(result.iterations),
        "reduced_chi2": _json_float(result.reduced_chi2),
        "equations": int(result.n_equations),
        "poses": int(result.residuals.shape[0]),
        "components": list(result.components),
        "names": list(result.names),
        "parameters": entries,
        "held": held,
        "covariance": np.asarray(result.covariance).tolist(),
        "cost_history": [_json_float(c) for c in result.cost_history],
        "residuals": {
            "before": _stats_dict(result.before),
            "after": _stats_dict(result.after),
            "per_pose_SI": np.asarray(result.residuals).tolist(),
        },
    }
    if result.initial_residuals is not None:
        doc["residuals"]["per_pose_before_SI"] = np.asarray(result.initial_residuals).tolist()
    if result.identifiability_summary is not None:
        doc["identifiability"] = _identifiability_dict(result.identifiability_summary)
    extras = _extras_dict(result.extras)
    if extras is not None:
        doc["extras"] = extras
    if result.weighting is not None:
        doc["weighting"] = result.weighting.to_dict()
    doc.update(notes)
    return doc
