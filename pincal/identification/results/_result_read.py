"""``identification.json``: the one reader, giving an :class:`IdentificationRecord`.

The format (version 2, SI values) is described in :mod:`pincal.identification.results._result_io`,
which writes it. Every value is checked on reading; a file without ``version`` (written by
pincal 0.1) or of a newer version is refused with what to do.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from pincal.errors import ReportError
from pincal.identification._weighting import Weighting
from pincal.identification.results._joint_details import JOINT_KEYS, JointDetails
from pincal.identification.results._result import (
    IdentifiabilitySummary,
    IdentificationRecord,
    LocalSolverExtras,
    QPSOExtras,
    ResidualStats,
    SolverExtras,
    StepPlanningExtras,
)
from pincal.identification.results._result_io import FORMAT_VERSION, OWNED, STATS
from pincal.model import joint_term_units

__all__ = ["result_from_dict"]

_KNOWN_COMPONENTS = ("x", "y", "z", "rx", "ry", "rz")


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


def _check_version(data: Mapping[str, Any], src: str) -> None:
    if "version" not in data:
        raise ReportError(
            f"{src} was written by pincal 0.1 (it has no 'version'); this pincal reads "
            f"identification format version {FORMAT_VERSION} only: re-run `pincal calibrate` "
            "on the data to write it again"
        )
    version = data["version"]
    if isinstance(version, bool) or not isinstance(version, int) or version < 1:
        raise ReportError(f"{src}: 'version' must be a positive integer, got {version!r}")
    if version > FORMAT_VERSION:
        raise ReportError(
            f"{src} has identification format version {version}, written by a newer pincal; "
            f"this pincal reads version {FORMAT_VERSION}; upgrade pincal"
        )
    if version < FORMAT_VERSION:
        raise ReportError(
            f"{src} has identification format version {version}, which this pincal no longer "
            f"reads (it reads version {FORMAT_VERSION}); re-run `pincal calibrate`"
        )


def _entries(data: Mapping[str, Any], src: str) -> tuple[list[dict], list[dict]]:
    params = data.get("parameters")
    if not isinstance(params, list) or not params:
        raise ReportError(f"{src}: 'parameters' must be a non-empty list")
    for k, p in enumerate(params):
        if not isinstance(p, dict) or not isinstance(p.get("name"), str):
            raise ReportError(f"{src}: parameters[{k}] must be an object with a 'name'")
        for key in ("value", "std", "initial"):
            _number(p.get(key), f"parameters[{k}].{key}", src)
        if p.get("unit", "m") not in ("m", "rad", *joint_term_units()):
            raise ReportError(
                f"{src}: parameters[{k}].unit must be 'm', 'rad' or a joint term's unit "
                f"({', '.join(sorted(joint_term_units()))}), got {p.get('unit')!r}"
            )
    held = data.get("held", [])
    if not isinstance(held, list):
        raise ReportError(f"{src}: 'held' must be a list of parameter objects")
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
    for key, _, f in STATS:
        v = d.get(key)
        vals.append(float("nan") if v is None else _number(v, f"{what}.{key}", src) / f)
    return ResidualStats(*vals)


def _read_extras(e: object, src: str) -> SolverExtras | None:
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


def _read_identifiability(value: object, src: str) -> IdentifiabilitySummary | None:
    """The identifiability summary (None when the file has none)."""
    if value is None:
        return None
    shape = "an object {parameters, rank, unidentifiable: [names], explanation: [lines]}"
    if not isinstance(value, dict):
        raise ReportError(f"{src}: 'identifiability' must be {shape}")
    n, rank = value.get("parameters"), value.get("rank")
    lists = [value.get("unidentifiable", []), value.get("explanation", []),
             value.get("breaks_closure", [])]  # fmt: skip
    counts_ok = all(isinstance(c, int) and not isinstance(c, bool) and c >= 0 for c in (n, rank))
    lists_ok = all(isinstance(x, list) and all(isinstance(t, str) for t in x) for x in lists)
    if not (counts_ok and lists_ok and isinstance(n, int) and isinstance(rank, int)):
        raise ReportError(f"{src}: 'identifiability' must be {shape}, got {str(value)[:120]}")
    return IdentifiabilitySummary(n, rank, tuple(lists[0]), tuple(lists[1]), tuple(lists[2]))


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


def _residual_tables(res: Mapping[str, Any], src: str) -> tuple[np.ndarray, np.ndarray | None]:
    """(m, c) residuals at the solution and, when recorded, at the start [m, rad]."""
    per_pose = res.get("per_pose_SI", [])
    try:
        residuals = np.array(per_pose, dtype=float).reshape(len(per_pose), -1 if per_pose else 0)
        if residuals.ndim != 2:
            raise ValueError("not a table")
    except (TypeError, ValueError):
        raise ReportError(f"{src}: residuals.per_pose_SI must be a list of number rows") from None
    initial_residuals = None
    if "per_pose_before_SI" in res:
        try:
            initial_residuals = np.array(res["per_pose_before_SI"], dtype=float)
        except (TypeError, ValueError):
            initial_residuals = None
        if initial_residuals is None or initial_residuals.shape != residuals.shape:
            raise ReportError(f"{src}: residuals.per_pose_before_SI must match per_pose_SI")
    return residuals, initial_residuals


def result_from_dict(
    data: Mapping[str, Any], source: str = "identification.json"
) -> IdentificationRecord:
    """Read a result document (format version 2).

    Args:
        data: the parsed JSON object.
        source: file name used in error messages.

    Returns:
        The :class:`IdentificationRecord`; top-level keys outside the format (and the
        parameters' ``true`` values, as ``truth``) in ``annotations``. Its mechanism is
        ``record.applied_to(nominal)`` (or the calibrated URDF of its directory).

    Raises:
        ReportError: a malformed document, one written by pincal 0.1 (no ``version``) or
            by a newer pincal.
    """
    src = source
    if not isinstance(data, Mapping):
        raise ReportError(f"{src} must hold a JSON object, got {type(data).__name__}")
    _check_version(data, src)
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
    std = np.array([float(p["std"]) for p in params])
    initial = np.array(
        [float(p["initial"] if f else p["value"]) for p, f in zip(every, flags, strict=True)]
    )
    if not isinstance(data.get("covariance"), list):
        raise ReportError(f"{src}: 'covariance' (of the identified parameters) is missing")
    cov = np.array(
        [_numbers(row, f"covariance[{i}]", src) for i, row in enumerate(data["covariance"])]
    )
    if cov.shape != (len(params), len(params)):
        raise ReportError(f"{src}: covariance must be {len(params)}×{len(params)}")
    history = _numbers(data.get("cost_history", []), "cost_history", src, allow_empty=True)
    res = data.get("residuals", {})
    res = res if isinstance(res, dict) else {}
    residuals, initial_residuals = _residual_tables(res, src)
    weighting = None
    if isinstance(data.get("weighting"), dict):
        try:
            weighting = Weighting.from_dict(data["weighting"])
        except (KeyError, TypeError, ValueError) as exc:
            raise ReportError(f"{src}: malformed 'weighting' ({exc})") from None
    notes = {k: v for k, v in data.items() if k not in OWNED}
    try:
        joint = JointDetails.from_dict(notes)
    except (AttributeError, TypeError, ValueError) as exc:
        raise ReportError(f"{src}: malformed joint-fit entries ({exc})") from None
    if joint is not None:
        notes = {k: v for k, v in notes.items() if k not in JOINT_KEYS}
    truth = {p["name"]: float(p["true"]) for p in every if "true" in p}
    if truth:
        notes["truth"] = truth
    chi2 = data.get("reduced_chi2")
    return IdentificationRecord(
        method=str(data.get("method", "unknown")),
        names=tuple(p["name"] for p in every),
        units=tuple(str(p.get("unit", "m")) for p in every),
        full_values=np.array([float(p["value"]) for p in every]),
        identified=np.array(flags),
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
        components=_read_components(data.get("components"), residuals, src),
        identifiability_summary=_read_identifiability(data.get("identifiability"), src),
        joint=joint,
    )
