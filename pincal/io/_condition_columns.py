"""Per-pose condition columns of a measurement file: the machine temperature.

An optional column ``temperature_C`` holds the machine's temperature at each pose in
degrees Celsius (°C), for the thermal-expansion term (``calibrate --model
geometric+temperature``, :mod:`pincal.model.params._term_temperature`). It is read into
:attr:`pincal.measure.Measurements.temperature` and written back by
:func:`pincal.io.write_measurements` (``simulate`` keeps it).
"""

from __future__ import annotations

import numpy as np

from pincal.errors import BadValueError

__all__ = ["TEMPERATURE_COLUMN", "TEMPERATURE_RANGE_C", "read_temperature"]

#: the column name (unit °C, in the name: a bracketed unit is not needed)
TEMPERATURE_COLUMN = "temperature_C"
#: plausible machine temperatures [°C]; a value outside is a typo or a Kelvin column
TEMPERATURE_RANGE_C = (-60.0, 200.0)


def read_temperature(values: np.ndarray, name: str) -> np.ndarray:
    """The checked (m,) temperatures [°C] of a file's ``temperature_C`` column.

    Raises:
        BadValueError: a value outside :data:`TEMPERATURE_RANGE_C` (naming its row).
    """
    T = np.asarray(values, dtype=float)
    lo, hi = TEMPERATURE_RANGE_C
    bad = np.flatnonzero(~((T >= lo) & (T <= hi)))
    if bad.size:
        i = int(bad[0])
        raise BadValueError(
            f"{name} data row {i + 1}, column {TEMPERATURE_COLUMN!r}: {T[i]:g} °C is outside "
            f"{lo:g}..{hi:g} °C; give the machine temperature in degrees Celsius",
            i + 1,
            TEMPERATURE_COLUMN,
        )
    return T
