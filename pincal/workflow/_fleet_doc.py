"""The fleet document (``fleet.json``): every unit, the test, the parameters' spread.

:func:`fleet_report` judges the calibrated units of a fleet run
(:func:`fleet_statistics`, when at least 3 were calibrated) and returns the document;
:func:`fleet_document` writes it up from a given judgement.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pincal.errors import PincalError
from pincal.executor import MapResult
from pincal.io import Fleet
from pincal.workflow._fleet_drift import DriftVerdict, session_drift
from pincal.workflow._fleet_stats import (
    DETECTION_POWER,
    FleetStatistics,
    UnitEstimate,
    fleet_statistics,
)

__all__ = ["FleetReport", "fleet_document", "fleet_report"]


@dataclass(frozen=True)
class FleetReport:
    """A fleet run judged.

    Attributes:
        document: ``fleet.json`` (:func:`fleet_document`), JSON-ready.
        warning: why there is no out-of-family test although ≥ 3 units were
            calibrated (the test's error message), else None.
    """

    document: dict[str, Any]
    warning: str | None = None


def fleet_report(
    fleet: Fleet, results: MapResult, alpha: float, out_rel: str = "units"
) -> FleetReport:
    """Compare the calibrated units of a fleet run and write up the fleet document.

    Args:
        fleet: the :class:`pincal.io.Fleet`.
        results: one result per unit, in fleet order; a value is a unit summary
            (``{status: "calibrated", id, names, values [m, rad], covariance [SI], …}``)
            or ``{status: "refused", reason}``.
        alpha: the fleet-wise false-alarm rate, in (0, 1).
        out_rel: the units' directory relative to the report.

    Returns:
        The :class:`FleetReport` (no test below 3 calibrated units, or when the test
        refuses the units: then its message is the warning). A unit calibrated in
        several sessions enters the out-of-family test with its latest session, and its
        consecutive sessions are compared for drift (:func:`session_drift`).
    """
    latest: dict[str, tuple[str, UnitEstimate]] = {}
    sessions = []
    for unit, res in zip(fleet.units, results, strict=True):
        if not (res.ok and res.value["status"] == "calibrated"):
            continue
        s = res.value
        est = UnitEstimate(
            unit.label, tuple(s["names"]), np.array(s["values"]), np.array(s["covariance"])
        )
        date = unit.meta.get("date", "") if unit.repeated else ""
        if unit.id not in latest or date > latest[unit.id][0]:
            latest[unit.id] = (date, est)
        if unit.repeated:
            sessions.append((unit.id, date, est))
    estimates = [est for _, est in latest.values()]
    stats, warning = None, None
    if len(estimates) >= 3:
        try:
            stats = fleet_statistics(estimates, alpha)
        except PincalError as exc:
            warning = str(exc)
    drift = session_drift(sessions, alpha)
    return FleetReport(fleet_document(fleet, results, stats, alpha, out_rel, drift), warning)


def _test_text(alpha: float, units: int, stats: FleetStatistics | None) -> str:
    if stats is None:
        return (
            f"no out-of-family test: it needs at least 3 calibrated units, {units} were calibrated"
        )
    bonferroni = stats.limit >= alpha / len(stats.units)
    limit = (
        f"α/M = {alpha:g}/{len(stats.units)} (Bonferroni"
        if bonferroni
        else f"{stats.limit:.3g}, calibrated by 200 fault-free fleets drawn from the fitted "
        f"family (on {len(stats.units)} units α/M alone flags in-family units far more often"
    )
    return (
        "Each calibrated unit's estimate x_u is compared with the fleet's robust centre c "
        "by D_u = (x_u − c)ᵀ (C_u + diag τ²)⁻¹ (x_u − c), with C_u the unit's own "
        "covariance and τ the production spread per parameter (maximum likelihood, robust: "
        "fitted on the 3/4 nearest units, then on every unit not rejected at p < 0.001); "
        f"in family D_u ~ χ²({len(stats.names)}). A unit is out of family when its p-value "
        f"is below {limit}: at most {100 * alpha:g} % chance of one or more false flags in "
        f"this fleet), i.e. D_u > {stats.threshold:.1f}. Assumes independent Gaussian "
        "spread per parameter and linearised estimation errors. A parameter's error alone "
        f"is flagged with {100 * DETECTION_POWER:g} % probability from the size in the "
        "parameters' 'detectable' column (median over the units: √(λ / [(C_u + diag τ²)⁻¹]_jj), "
        "λ the noncentrality of that power); an error below it, however real, these "
        "calibrations do not tell from the family."
    )


def fleet_document(
    fleet: Fleet,
    results: MapResult,
    stats: FleetStatistics | None,
    alpha: float,
    out_rel: str,
    drift: tuple[DriftVerdict, ...] = (),
) -> dict[str, Any]:
    """``fleet.json``: every unit ``{id, status, out_of_family, distance, p_value, …}``.

    Args:
        fleet: the :class:`pincal.io.Fleet`.
        results: the executor's :class:`pincal.executor.MapResult`, one per unit.
        stats: the :class:`FleetStatistics`, or None (< 3 calibrated).
        alpha: the fleet-wise false-alarm rate.
        out_rel: the units' directory relative to the report (``units``).
        drift: the drift verdicts of units calibrated more than once.

    Returns:
        The document (JSON-ready).
    """
    verdicts = {v.id: v for v in stats.units} if stats is not None else {}
    compared = set(stats.names) if stats is not None else set()
    units = []
    for unit, res in zip(fleet.units, results, strict=True):
        entry: dict[str, Any] = {"id": unit.id, "data": str(unit.data), **unit.meta}
        if unit.repeated:
            entry["session"] = unit.label
        if not res.ok:
            entry |= {
                "status": "failed",
                "reason": res.error,
                "out_of_family": None,
                "distance": None,
                "p_value": None,
            }
        elif res.value["status"] == "refused":
            entry |= {
                "status": "refused",
                "reason": res.value["reason"],
                "out_of_family": None,
                "distance": None,
                "p_value": None,
            }
        else:
            s = res.value
            v = verdicts.get(unit.label)
            entry |= {
                "status": "calibrated",
                "calibration": f"{out_rel}/{unit.label}",
                "out_of_family": None if v is None else v.out_of_family,
                "distance": None if v is None else v.distance,
                "dof": None if v is None else v.dof,
                "p_value": None if v is None else v.p_value,
                "largest": [] if v is None else [{"name": n, "z": z} for n, z in v.largest],
                **(
                    {"reason": "an earlier session: compared for drift"}
                    if v is None and stats is not None and unit.repeated
                    else {}
                ),
                "reused": bool(s.get("reused") or res.cached),
                "rms_after_mm": s.get("rms_after_mm"),
                "values": {
                    n: x for n, x in zip(s["names"], s["values"], strict=True) if n in compared
                },
            }
        units.append(entry)
    count = {k: sum(u["status"] == k for u in units) for k in ("calibrated", "refused", "failed")}
    flagged = [u["id"] for u in units if u.get("out_of_family")]
    drifted = [d.id for d in drift if d.drifted]
    unit_of: dict[str, str] = {}
    for res in results:
        if res.ok and res.value["status"] == "calibrated":
            unit_of |= dict(zip(res.value["names"], res.value["units"], strict=True))
    params = []
    if stats is not None:
        for j, name in enumerate(stats.names):
            params.append(
                {
                    "name": name,
                    "unit": unit_of.get(name, "m"),
                    "centre": float(stats.centre[j]),
                    "production_std": float(stats.production_std[j]),
                    "estimate_std": float(stats.estimate_std[j]),
                    "detectable_error": float(stats.detectable[j]),
                }
            )
    return {
        "format": "pincal fleet",
        "version": 1,
        "fleet": str(fleet.path),
        "model": fleet.model,
        "preset": fleet.preset,
        "summary": {
            "units": len(units),
            "unit_ids": len({u.id for u in fleet.units}),
            **count,
            "out_of_family": len(flagged),
            "out_of_family_ids": flagged,
            "drift_compared": len(drift),
            "drifted": len(drifted),
            "drifted_ids": drifted,
        },
        "test": {
            "statistic": "squared Mahalanobis distance to the robust fleet centre, "
            "covariance = unit covariance + diag(production spread²)",
            "alpha": alpha,
            "correction": "bonferroni"
            if stats is None or stats.limit >= alpha / len(stats.units)
            else "calibrated by fault-free fleets",
            "per_unit_p_threshold": None if stats is None else stats.limit,
            "dof": None if stats is None else len(stats.names),
            "distance_threshold": None if stats is None else stats.threshold,
            "description": _test_text(alpha, count["calibrated"], stats),
        },
        "units": units,
        "parameters": params,
        "drift": [
            {
                "id": d.id,
                "before": d.before,
                "after": d.after,
                "drifted": d.drifted,
                "distance": d.distance,
                "dof": d.dof,
                "p_value": d.p_value,
                "largest": [
                    {"name": n, "z": z, "change": c, "unit": unit_of.get(n, "m")}
                    for n, z, c in d.largest
                ],
            }
            for d in drift
        ],
        "drift_test": _drift_text(alpha, drift),
    }


def _drift_text(alpha: float, drift: tuple[DriftVerdict, ...]) -> str:
    if not drift:
        return "no unit was calibrated in more than one session: no drift compared"
    return (
        "Consecutive calibrations x₁, x₂ of a unit are compared by T² = dᵀ(C₁ + C₂)⁺d, "
        "d = x₂ − x₁, over the parameters both identified (χ²(rank) without drift). A "
        f"unit drifted when p < α/K = {alpha:g}/{len(drift)} (Bonferroni over the "
        f"{len(drift)} comparisons: at most {100 * alpha:g} % chance of one or more false "
        "drifts), as far as each calibration's covariance is its whole error: unmodelled "
        "errors that differ between the sessions' poses show as drift. The out-of-family "
        "test takes each unit's latest session."
    )
