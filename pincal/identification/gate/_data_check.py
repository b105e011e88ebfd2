"""The quality gate's look at the data before fitting: length scale, duplicate rows."""

from __future__ import annotations

import math

import numpy as np

from pincal.errors import PincalError
from pincal.identification._verdict import GateLimits, QualityIssue, QualityVerdict
from pincal.measure import Measurements
from pincal.model import Mechanism

__all__ = ["check_measurements"]

#: length units a file may really be in [m per unit]
_UNITS = {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6, "in": 0.0254, "ft": 0.3048}
#: length units a pincal measurement file can declare
_READABLE = ("m", "mm", "um")
#: a spread ratio outside the band refuses only when the spreads differ by more [m]
#: (honest geometric errors cannot change the spread of the poses that much)
_MIN_SPREAD_CHANGE = 2e-3
#: scale ratio within this relative distance (in log) of a unit ratio names that unit
_UNIT_MATCH = 0.15


def _duplicates(meas: Measurements) -> tuple[tuple[int, int], ...]:
    """(copy, original) pairs of rows with identical actuator values and measurement."""
    parts = [meas.q_act, meas.positions]
    if meas.rotations is not None:
        parts.append(meas.rotations.reshape(len(meas), 9))
    rows = np.ascontiguousarray(np.hstack(parts))
    seen: dict[bytes, int] = {}
    out = []
    for i, row in enumerate(rows):
        key = row.tobytes()
        if key in seen:
            out.append((i, seen[key]))
        else:
            seen[key] = i
    return tuple(out)


def _nominal_poses(
    mech: Mechanism, q_act: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Nominal positions (m, 3), rotations (m, 3, 3) and a mask of the rows that solved."""
    pos, rot = np.full((len(q_act), 3), np.nan), np.full((len(q_act), 3, 3), np.nan)
    try:
        for i, q in enumerate(mech.configurations(q_act)):
            T = mech.frame_placement(q)
            pos[i], rot[i] = T.translation, T.rotation
    except PincalError:
        for i, row in enumerate(q_act):
            try:
                T = mech.forward(row)
            except PincalError:
                continue
            pos[i], rot[i] = T.translation, T.rotation
    return pos, rot, np.all(np.isfinite(pos), axis=1)


def _mean_rotation_angle(measured: np.ndarray, nominal: np.ndarray) -> float:
    """Angle [rad] of the chordal mean of ``R_meas R_nomᵀ`` (a world-frame rotation)."""
    M = np.einsum("mij,mkj->ik", measured, nominal)
    U, _, Vt = np.linalg.svd(M)
    R = U @ np.diag([1.0, 1.0, np.linalg.det(U @ Vt)]) @ Vt
    return float(np.arccos(np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0)))


def _spread(p: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.sum((p - p.mean(axis=0)) ** 2, axis=1))))


def _unit_of(ratio: float, declared: str) -> str | None:
    """The unit the data are likely in, given measured/nominal spread ``ratio``."""
    if not (math.isfinite(ratio) and ratio > 0):
        return None
    f_declared = _UNITS.get(declared, 1.0)
    f_true = f_declared / ratio  # value·f_declared = x·ratio → the file holds x / f_true
    best = min(_UNITS, key=lambda u: abs(math.log(_UNITS[u] / f_true)))
    if best != declared and abs(math.log(_UNITS[best] / f_true)) < _UNIT_MATCH:
        return best
    return None


def check_measurements(
    mech: Mechanism,
    measurements: Measurements,
    *,
    length_unit: str = "m",
    limits: GateLimits | None = None,
) -> QualityVerdict:
    """The gate's look at the data before fitting: length scale and duplicate rows.

    The spread of the measured positions about their centroid is compared with the
    spread of the nominal model's positions at the same actuator values (a rigid frame
    offset changes neither); a ratio outside ``[1/scale_band, scale_band]`` refuses and
    names the unit the data are likely in. Exact duplicate rows (same actuator values,
    same measurement) are a warning: each copy shrinks the reported σ.

    Args:
        mech: the nominal mechanism.
        measurements: the measured poses [SI as read].
        length_unit: the length unit the file declared (``m``, ``mm``, ``um``, ``cm``...).
        limits: thresholds (default :class:`GateLimits`).

    Returns:
        QualityVerdict (``cause`` ``units`` when the scale refuses).
    """
    lim = limits or GateLimits()
    issues: list[QualityIssue] = []
    dup = _duplicates(measurements)
    if dup:
        shown = ", ".join(f"{c}={o}" for c, o in dup[:6]) + (" …" if len(dup) > 6 else "")
        issues.append(QualityIssue(
            "duplicates", False,
            f"{len(dup)} of {len(measurements)} rows repeat an earlier row exactly (rows "
            f"{shown}): each copy shrinks the reported σ without new information; remove "
            "copied rows",
        ))  # fmt: skip
    ratio, unit, offset, rotation = float("nan"), None, float("nan"), float("nan")
    cause, text = "", ""
    if any(c in ("x", "y", "z") for c in measurements.components) and len(measurements) >= 3:
        nominal, nominal_rot, ok = _nominal_poses(mech, measurements.q_act)
        if measurements.rotations is not None and ok.sum() >= 3:
            rotation = _mean_rotation_angle(measurements.rotations[ok], nominal_rot[ok])
        measured = measurements.positions[ok]
        s_nom = _spread(nominal[ok]) if ok.sum() >= 3 else 0.0
        if s_nom > 1e-6:
            ratio = _spread(measured) / s_nom
            offset = float(np.linalg.norm(measured.mean(axis=0) - nominal[ok].mean(axis=0)))
            s_meas = _spread(measured)
            if not 1.0 / lim.scale_band <= ratio <= lim.scale_band and (
                abs(s_meas - s_nom) > _MIN_SPREAD_CHANGE
            ):
                unit = _unit_of(ratio, length_unit)
                fix = (
                    f"set length_unit {unit}"
                    if unit is None or unit in _READABLE
                    else f"convert the values to mm (× {_UNITS[unit] / 1e-3:g})"
                )
                guess = (
                    f"the data look like {unit} declared as {length_unit}: {fix}"
                    if unit
                    else "no common unit explains it: check length_unit and the model"
                )
                issues.append(QualityIssue(
                    "units", True,
                    f"measured positions spread {ratio:.3g}× as much as the nominal model's at "
                    f"the same actuator values ({s_meas * 1e3:.4g} mm vs "
                    f"{s_nom * 1e3:.4g} mm; accepted {1 / lim.scale_band:g}–{lim.scale_band:g}×)",
                ))  # fmt: skip
                cause, text = "units", f"{guess}."
    return QualityVerdict(tuple(issues), cause, text, (), float("nan"), dup, ratio, unit,
                          (), offset, rotation, lim)  # fmt: skip
