"""Stage 6 — using the calibration: commands that reach targets with the calibrated model.

Actuator commands that bring the calibrated model to target poses, in the components the
machine controls.
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
