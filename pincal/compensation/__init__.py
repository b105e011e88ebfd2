"""Stage 6 — using the calibration: actuator commands that bring the calibrated model to
target poses.
"""

from __future__ import annotations

from pincal.compensation._compensate import (
    Compensation,
    compensate,
    compensation_components,
    poses_from_array,
)

__all__ = [
    "Compensation",
    "compensate",
    "compensation_components",
    "poses_from_array",
]
