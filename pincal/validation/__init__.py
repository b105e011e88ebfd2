"""Stage 6 — judge a calibration against measurements it was not fitted to.

Held-out validation (before/after errors, an ISO 9283 pose-accuracy table and the
Cramér–Rao prediction of the validation RMS), pose errors of a model against a
reference, and ISO 9283 pose characteristics with their test cube. Comes after
identification, beside :mod:`pincal.compensation`; imports :mod:`pincal.model`,
:mod:`pincal.sensitivity`, :mod:`pincal.measure` and :mod:`pincal.design` (never a
later stage).
"""

from __future__ import annotations

from pincal.validation._cv_summary import (
    CrossValidationBaseline,
    CrossValidationSummary,
    OrientationErrors,
)
from pincal.validation._held_out import (
    HeldOutValidation,
    prediction_caveat,
    validate_held_out,
)
from pincal.validation._iso9283 import (
    ORIENTATION_CONVENTION,
    PointAccuracy,
    PoseCharacteristics,
    point_accuracy,
    pose_characteristics,
    simulate_cycles,
)
from pincal.validation._iso_cube import (
    TestCube,
    iso_test_cube,
)
from pincal.validation._marker_errors import (
    MarkerErrors,
    marker_errors,
)
from pincal.validation._pose_errors import (
    PoseErrors,
    pose_errors,
)

__all__ = [
    "ORIENTATION_CONVENTION",
    "CrossValidationBaseline",
    "CrossValidationSummary",
    "HeldOutValidation",
    "MarkerErrors",
    "OrientationErrors",
    "PointAccuracy",
    "PoseCharacteristics",
    "PoseErrors",
    "TestCube",
    "iso_test_cube",
    "marker_errors",
    "point_accuracy",
    "pose_characteristics",
    "pose_errors",
    "prediction_caveat",
    "simulate_cycles",
    "validate_held_out",
]
