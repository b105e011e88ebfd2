"""Stage 6 — using the calibration: commands that reach targets with the calibrated model.

Actuator commands that bring the calibrated model to target poses, in the components the
machine controls.
"""

from __future__ import annotations

from pincal.compensation._branch import BRANCH_STEP_M, BRANCH_STEP_RAD, branch_change
from pincal.compensation._compensate import (
    Compensation,
    compensate,
    compensation_components,
    poses_from_array,
)
from pincal.compensation._joint_terms import JointTermCorrection

__all__ = [
    "BRANCH_STEP_M",
    "BRANCH_STEP_RAD",
    "Compensation",
    "JointTermCorrection",
    "branch_change",
    "compensate",
    "compensation_components",
    "poses_from_array",
]
