"""Units of the CSV files: length and angle unit tables and the conversion factors.

A factor is "units per SI unit": ``value_in_unit = SI value × factor``, so reading
divides by it and writing multiplies by it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from pincal._yaml import shown
from pincal.errors import ActuatorRangeError, MeasurementError, MeasurementFormatError
from pincal.model import Mechanism

__all__ = [
    "ANGLE_UNITS",
    "LENGTH_UNITS",
    "actuator_read_factors",
    "actuator_write_factors",
    "check_actuator_ranges",
    "si_actuator_units",
    "unit_factor",
]

#: how far past a URDF limit an actuator value is still read, as a fraction of the range
RANGE_TOLERANCE = 0.05
#: ranges wider than this [m or rad] are treated as "no range" (URDF ±1e308 and the like)
_NO_RANGE = 1e9

#: units per SI unit (value_in_unit = SI value × factor)
LENGTH_UNITS = {"m": 1.0, "mm": 1e3, "um": 1e6}
ANGLE_UNITS = {"rad": 1.0, "mrad": 1e3, "urad": 1e6, "deg": 180.0 / math.pi}


def unit_factor(table: dict[str, float], name: str, what: str, where: str) -> float:
    """Factor of unit ``name`` in ``table`` (:data:`LENGTH_UNITS` or :data:`ANGLE_UNITS`).

    Args:
        table: the unit table to look ``name`` up in.
        name: the unit as written in the file or passed by the caller.
        what: ``"length"`` or ``"angle"`` (for the message).
        where: file or function name (for the message).

    Returns:
        Units per SI unit [-].

    Raises:
        MeasurementFormatError: ``name`` is not in ``table``.
    """
    if name not in table:
        raise MeasurementFormatError(
            f"{where}: unknown {what} unit {shown(name)}; use one of {', '.join(table)}"
        )
    return table[name]


def actuator_read_factors(mech: Mechanism, units: list[str | None], name: str) -> np.ndarray:
    """Factors (n_act,) of the actuator columns' bracketed units (None = SI → 1).

    A revolute or continuous joint takes an angle unit, any other joint a length unit.

    Raises:
        MeasurementFormatError: a unit unknown for its joint's kind.
    """
    factors = []
    for joint, unit in zip(mech.actuated, units, strict=True):
        if unit is None:
            factors.append(1.0)
            continue
        revolute = mech.tree.joints[joint].type in ("revolute", "continuous")
        table = ANGLE_UNITS if revolute else LENGTH_UNITS
        factors.append(
            unit_factor(table, unit, "angle" if revolute else "length", f"{name} {joint}")
        )
    return np.array(factors)


def actuator_write_factors(units: Sequence[str] | None, n: int) -> np.ndarray:
    """Factors (n,) for writing ``n`` actuator columns in ``units`` (None = SI).

    Raises:
        MeasurementError: a unit that is neither a length nor an angle unit.
    """
    if units is None:
        return np.ones(n)
    table = {**LENGTH_UNITS, **ANGLE_UNITS}
    unknown = [u for u in units if u not in table]
    if unknown:
        raise MeasurementError(
            f"actuator units {shown(unknown)} unknown; use length units {', '.join(LENGTH_UNITS)} "
            f"or angle units {', '.join(ANGLE_UNITS)}"
        )
    return np.array([table[u] for u in units])


def si_actuator_units(mech: Mechanism) -> list[str]:
    """SI unit per actuated joint (n_act,), for files whose actuator columns state their unit.

    Returns:
        ``"rad"`` for revolute and continuous joints, ``"m"`` otherwise.
    """
    return [
        "rad" if mech.tree.joints[j].type in ("revolute", "continuous") else "m"
        for j in mech.actuated
    ]


def check_actuator_ranges(
    mech: Mechanism,
    q_act: np.ndarray,
    name: str,
    columns: Sequence[str] | None = None,
    lines: Sequence[int] | None = None,
) -> None:
    """Refuse actuator values far outside the joints' URDF limits.

    A value may exceed a limit by :data:`RANGE_TOLERANCE` of the joint's range
    (measured values scatter around the limits); joints without a finite range
    (continuous joints, prismatic joints without limits) are not checked.

    Args:
        mech: the model giving the actuated joints and their limits.
        q_act: (m, n_act) actuator values [m, rad], in ``mech.actuated`` order.
        name: file name, for the message.
        columns: the file's column title per actuator (default the joint names).
        lines: 1-based file line of each row (default: data rows 1 … m are named).

    Raises:
        ActuatorRangeError: the first value out of range (row, column, joint, range).
    """
    q_act = np.asarray(q_act, dtype=float).reshape(-1, len(mech.actuated))
    for k, joint in enumerate(mech.actuated):
        lo, hi = (float(v) for v in mech.actuator_limits[k])
        if not (np.isfinite(lo) and np.isfinite(hi) and 0 < hi - lo < _NO_RANGE):
            continue
        tol = RANGE_TOLERANCE * (hi - lo)
        bad = np.nonzero(~((q_act[:, k] >= lo - tol) & (q_act[:, k] <= hi + tol)))[0]
        if not bad.size:
            continue
        i = int(bad[0])
        col = joint if columns is None else columns[k]
        row = f"data row {i + 1}" if lines is None else f"line {lines[i]}"
        unit = "rad" if mech.tree.joints[joint].type in ("revolute", "continuous") else "m"
        raise ActuatorRangeError(
            f"{name} {row}, column {shown(col)}: joint {joint!r} = {q_act[i, k]:.6g} {unit} "
            f"is outside its range [{lo:.6g}, {hi:.6g}] {unit} (URDF limits, "
            f"{RANGE_TOLERANCE:.0%} of the range tolerated); check the column's unit and "
            "the joint order",
            i + 1,
            col,
            joint,
            (lo, hi),
        )
