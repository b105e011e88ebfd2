"""Units of the CSV files: length and angle unit tables and the conversion factors.

A factor is "units per SI unit": ``value_in_unit = SI value × factor``, so reading
divides by it and writing multiplies by it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from pincal._yaml import shown
from pincal.errors import MeasurementError, MeasurementFormatError
from pincal.model import Mechanism

__all__ = [
    "ANGLE_UNITS",
    "LENGTH_UNITS",
    "actuator_read_factors",
    "actuator_write_factors",
    "si_actuator_units",
    "unit_factor",
]

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
