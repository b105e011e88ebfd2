"""Held-out errors of the further markers of a marker calibration, each in its own frame.

`pincal validate --data` on a marker table with several distinct markers judges the
first marker in the full validation and each further one here: its position error before
(the nominal model) and after calibration [m]; :func:`pincal.report.marker_error_lines`
prints them.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from pincal.measure import Measurements
from pincal.model import Mechanism
from pincal.validation._cross_validation import position_errors

__all__ = ["MarkerErrors", "marker_errors"]


@dataclass(frozen=True, eq=False)
class MarkerErrors:
    """Position errors of one further marker at the held-out poses.

    Attributes:
        columns: the marker's (x, y, z) columns in the table.
        before: (m,) position error of the nominal model per pose [m].
        after: (m,) position error of the calibrated model per pose [m].
    """

    columns: tuple[str, ...]
    before: np.ndarray
    after: np.ndarray

    def to_dict(self) -> dict[str, Any]:
        """RMS before / after and max after [mm], for ``validate --json``."""
        before, after = self.before * 1e3, self.after * 1e3
        return {
            "columns": list(self.columns),
            "before_rms_position_mm": float(np.sqrt(np.mean(before**2))),
            "after_rms_position_mm": float(np.sqrt(np.mean(after**2))),
            "after_max_position_mm": float(after.max()),
        }


def marker_errors(
    nominal: Mechanism,
    calibrated: Mechanism,
    markers: Sequence[tuple[Sequence[str], Measurements]],
) -> list[MarkerErrors]:
    """The errors of each further marker (its columns, its measurements).

    Args:
        nominal: the nominal model (each marker's measurements name its frame).
        calibrated: the calibrated model.
        markers: per further marker its (x, y, z) columns and its held-out measurements.
    """
    return [MarkerErrors(tuple(columns), position_errors(nominal, part),
                         position_errors(calibrated, part))
            for columns, part in markers]  # fmt: skip
