"""``identification.json``: the one writer and reader of an identification result.

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

Files of pincal 0.1 (no ``version``; written by ``pincal calibrate`` or ``pincal demo``)
are read too: their covariance is diagonal (from ``std``) and their held parameters sit
at zero.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from pincal.errors import ReportError
from pincal.identification._result import (
    IdentificationResult,
    LocalSolverExtras,
    QPSOExtras,
    ResidualStats,
    StepPlanningExtras,
)
from pincal.identification._weighting import Weighting
from pincal.model import joint_term_units

__all__ = ["FORMAT_NAME", "FORMAT_VERSION", "result_from_dict", "result_to_dict"]

FORMAT_NAME = "pincal identification"
FORMAT_VERSION = 2
_OWNED = {
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
    "fixed",
    "covariance",
    "cost_history",
    "residuals",
    "identifiability",
    "extras",
    "weighting",
}
_STATS = (
    ("rms_position_mm", "rms_position", 1e3),
    ("max_position_mm", "max_position", 1e3),
    ("rms_orientation_mrad", "rms_orientation", 1e3),
    ("max_orientation_mrad", "max_orientation", 1e3),
)


def _json_float(v: float) -> float | None:
    return None if not math.isfinite(float(v)) else float(v)


def _stats_dict(s: ResidualStats) -> dict[str, float | None]:
    out = {}
    for key, attr, f in _STATS:
        v = getattr(s, attr)
        out[key] = None if math.isnan(v) else v * f
    return out


def _extras_dict(e) -> dict[str, Any] | None:
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


def result_to_dict(
    result: IdentificationResult, annotations: Mapping[str, Any] | None = None
) -> dict[str, Any]:
    """The JSON document of ``result`` (format version 2, SI values).

    Args:
        result: the identification result.
        annotations: JSON-ready context added at the top level (merged over
            ``result.annotations``). The key ``truth`` ({name: value [SI]}) is written as
            ``true`` in the parameter entries.

    Raises:
        ReportError: an annotation would overwrite a key of the result.
    """
    notes = dict(result.annotations)
    notes.update(annotations or {})
    passthrough = {"identifiability"} if result.identifiability is None else set()
    clash = sorted(set(notes) & (_OWNED - passthrough))
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
    ident = result.identifiability
    if ident is not None:
        doc["identifiability"] = {
            "parameters": len(ident.names),
            "rank": ident.rank,
            "unidentifiable": list(ident.unidentifiable_names),
            "explanation": ident.describe(),
        }
    extras = _extras_dict(result.extras)
    if extras is not None:
        doc["extras"] = extras
    if result.weighting is not None:
        doc["weighting"] = result.weighting.to_dict()
    doc.update(notes)
    return doc


# --------------------------------------------------------------------------- reading


def _number(value: object, what: str, src: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ReportError(f"{src}: {what} must be a number, got {value!r}")
    if not math.isfinite(float(value)):
        raise ReportError(f"{src}: {what} is NaN or infinite")
    return float(value)


def _numbers(value: object, what: str, src: str, allow_empty: bool = False) -> np.ndarray:
    if not isinstance(value, list) or (not value and not allow_empty):
        raise ReportError(f"{src}: {what} must be a non-empty list of numbers")
    return np.array([_number(v, f"{what}[{k}]", src) for k, v in enumerate(value)], dtype=float)


def _guess_unit(name: str) -> str:
    dof = name.rsplit(".", 1)[-1]
    return "rad" if dof in ("rx", "ry", "rz") or dof.startswith(("alpha", "theta")) else "m"


def _entries(data: Mapping[str, Any], src: str) -> tuple[list[dict], list[dict]]:
    params = data.get("parameters")
    if not isinstance(params, list) or not params:
        raise ReportError(f"{src}: 'parameters' must be a non-empty list")
    for k, p in enumerate(params):
        if not isinstance(p, dict) or not isinstance(p.get("name"), str):
            raise ReportError(f"{src}: parameters[{k}] must be an object with a 'name'")
        for key in ("value", "std"):
            _number(p.get(key), f"parameters[{k}].{key}", src)
        if p.get("unit", "m") not in ("m", "rad", *joint_term_units()):
            raise ReportError(
                f"{src}: parameters[{k}].unit must be 'm', 'rad' or a joint term's unit "
                f"({', '.join(sorted(joint_term_units()))}), got {p.get('unit')!r}"
            )
    held = data.get("held", [])
    if not isinstance(held, list):
        raise ReportError(f"{src}: 'held' must be a list of parameter objects")
    if "held" not in data and isinstance(data.get("fixed"), list):  # pincal 0.1: names only
        held = [{"name": str(n), "unit": _guess_unit(str(n)), "value": 0.0} for n in data["fixed"]]
    for k, p in enumerate(held):
        if not isinstance(p, dict) or not isinstance(p.get("name"), str):
            raise ReportError(f"{src}: held[{k}] must be an object with a 'name'")
        _number(p.get("value"), f"held[{k}].value", src)
    for group, what in ((params, "parameters"), (held, "held")):
        for k, p in enumerate(group):
            if "true" in p:
                _number(p["true"], f"{what}[{k}].true", src)
    return params, held


def _stats(d: object, src: str, what: str) -> ResidualStats:
    vals = []
    d = d if isinstance(d, dict) else {}
    for key, _, f in _STATS:
        v = d.get(key)
        vals.append(float("nan") if v is None else _number(v, f"{what}.{key}", src) / f)
    return ResidualStats(*vals)


def _read_extras(e: object, src: str):
    if not isinstance(e, dict):
        return None
    try:
        kind = e["type"]
        if kind == "local":
            damping = e.get("damping")
            return LocalSolverExtras(
                int(e["evaluations"]),
                int(e.get("rejected_steps", 0)),
                float("nan") if damping is None else float(damping),
            )
        if kind == "qpso":
            nan = float("nan")
            return QPSOExtras(
                nan if e["cost"] is None else float(e["cost"]),
                nan if e["initial_cost"] is None else float(e["initial_cost"]),
                int(e["nfev"]),
                tuple(int(i) for i in e["order"]),
                float(e["seconds"]),
                tuple(nan if v is None else float(v) for v in e["swarm_history"]),
            )
        if kind == "step-planned":
            return StepPlanningExtras(np.array(e["steps"], float), np.array(e["weights"], float))
    except (KeyError, TypeError, ValueError) as exc:
        raise ReportError(f"{src}: malformed 'extras' ({exc})") from None
    raise ReportError(f"{src}: unknown extras type {e.get('type')!r}")


_KNOWN_COMPONENTS = ("x", "y", "z", "rx", "ry", "rz")


def _read_components(value: object, residuals: np.ndarray, src: str) -> tuple[str, ...]:
    """The residual columns' component names (empty when the file does not say)."""
    if value is None or value == []:
        return ()
    if (
        not isinstance(value, list)
        or not all(isinstance(c, str) and c in _KNOWN_COMPONENTS for c in value)
        or len(set(value)) != len(value)
    ):
        raise ReportError(
            f"{src}: 'components' must list distinct names from {' '.join(_KNOWN_COMPONENTS)}, "
            f"got {value!r}"
        )
    if residuals.size and residuals.shape[1] != len(value):
        raise ReportError(
            f"{src}: 'components' names {len(value)} columns but the residuals have "
            f"{residuals.shape[1]}"
        )
    return tuple(value)


def result_from_dict(data: Mapping[str, Any], source: str = "identification.json"):
    """Read a result document (format version 2, or pincal 0.1 without ``version``).

    Args:
        data: the parsed JSON object.
        source: file name used in error messages.

    Returns:
        IdentificationResult with ``parameter_set``, ``calibrated`` and
        ``identifiability`` None; top-level keys outside the format (and the
        parameters' ``true`` values, as ``truth``) in ``annotations``.

    Raises:
        ReportError: a malformed document, or one written by a newer pincal.
    """
    src = source
    if not isinstance(data, Mapping):
        raise ReportError(f"{src} must hold a JSON object, got {type(data).__name__}")
    version = data.get("version", 1)
    if isinstance(version, bool) or not isinstance(version, int) or version < 1:
        raise ReportError(f"{src}: 'version' must be a positive integer, got {version!r}")
    if version > FORMAT_VERSION:
        raise ReportError(
            f"{src} has identification format version {version}, written by a newer pincal; "
            f"this pincal reads versions 1 (pincal 0.1) to {FORMAT_VERSION}; upgrade pincal"
        )
    if not isinstance(data.get("model"), str):
        raise ReportError(f"{src}: 'model' (the model name) is missing")
    params, held = _entries(data, src)
    every = params + held
    flags = [True] * len(params) + [False] * len(held)
    order = data.get("names")
    if order is not None:  # the parameter order of the set (identified and held mixed)
        if not isinstance(order, list) or sorted(order) != sorted(p["name"] for p in every):
            raise ReportError(f"{src}: 'names' must list the parameters and held ones")
        where = {p["name"]: k for k, p in enumerate(every)}
        perm = [where[n] for n in order]
        every, flags = [every[k] for k in perm], [flags[k] for k in perm]
        params = [p for p, f in zip(every, flags, strict=True) if f]
    names = tuple(p["name"] for p in every)
    identified = np.array(flags)
    full = np.array([float(p["value"]) for p in every])
    std = np.array([float(p["std"]) for p in params])
    initial = np.array(
        [
            float(p.get("initial", 0.0)) if f else float(p["value"])
            for p, f in zip(every, flags, strict=True)
        ]
    )
    cov = np.diag(std**2)
    if "covariance" in data:
        cov = np.array(
            [_numbers(row, f"covariance[{i}]", src) for i, row in enumerate(data["covariance"])]
        )
        if cov.shape != (len(params), len(params)):
            raise ReportError(f"{src}: covariance must be {len(params)}×{len(params)}")
    history = data.get("cost_history", [])
    history = _numbers(history, "cost_history", src, allow_empty=True)
    res = data.get("residuals", {})
    res = res if isinstance(res, dict) else {}
    per_pose = res.get("per_pose_SI", [])
    try:
        residuals = np.array(per_pose, dtype=float).reshape(len(per_pose), -1 if per_pose else 0)
        if residuals.ndim != 2:
            raise ValueError("not a table")
    except (TypeError, ValueError):
        raise ReportError(f"{src}: residuals.per_pose_SI must be a list of number rows") from None
    chi2 = data.get("reduced_chi2")
    initial_residuals = None
    if "per_pose_before_SI" in res:
        try:
            initial_residuals = np.array(res["per_pose_before_SI"], dtype=float)
        except (TypeError, ValueError):
            initial_residuals = None
        if initial_residuals is None or initial_residuals.shape != residuals.shape:
            raise ReportError(f"{src}: residuals.per_pose_before_SI must match per_pose_SI")
    components = _read_components(data.get("components"), residuals, src)
    weighting = None
    if isinstance(data.get("weighting"), dict):
        try:
            weighting = Weighting.from_dict(data["weighting"])
        except (KeyError, TypeError, ValueError) as exc:
            raise ReportError(f"{src}: malformed 'weighting' ({exc})") from None
    notes = {k: v for k, v in data.items() if k not in _OWNED}
    truth = {p["name"]: float(p["true"]) for p in every if "true" in p}
    if truth:
        notes["truth"] = truth
    if "identifiability" in data:  # written again by to_dict (no analysis object here)
        notes["identifiability"] = data["identifiability"]
    return IdentificationResult(
        method=str(data.get("method", "unknown")),
        names=names,
        units=tuple(str(p.get("unit", "m")) for p in every),
        full_values=full,
        identified=identified,
        std=std,
        covariance=cov,
        before=_stats(res.get("before"), src, "residuals.before"),
        after=_stats(res.get("after"), src, "residuals.after"),
        reduced_chi2=float("nan") if chi2 is None else _number(chi2, "reduced_chi2", src),
        iterations=int(_number(data.get("iterations", 0), "iterations", src)),
        success=bool(data.get("success", True)),
        message=str(data.get("message", "")),
        cost_history=tuple(history.tolist()),
        residuals=residuals,
        initial_values=initial,
        n_equations=int(_number(data.get("equations", residuals.size), "equations", src)),
        model=data["model"],
        preset=str(data.get("preset", "")),
        extras=_read_extras(data.get("extras"), src),
        annotations=notes,
        weighting=weighting,
        initial_residuals=initial_residuals,
        components=components,
    )
