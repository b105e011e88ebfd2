"""Stage 6 — judge a calibration against measurements it was not fitted to.

K-fold cross-validation of a fitting procedure over the poses (:func:`cross_validate`,
:func:`compare`) and the held-out gate it feeds (:func:`held_out_verdict`); model
selection by cross-validation (:func:`select_model`); Monte-Carlo identification studies
(:func:`monte_carlo`); held-out validation (before/after errors, an ISO 9283 pose-accuracy
table and the Cramér–Rao prediction of the validation RMS), pose errors of a model
against a reference, and ISO 9283 pose characteristics with their test cube. Comes after
identification, beside :mod:`pincal.compensation`; imports :mod:`pincal.model`,
:mod:`pincal.sensitivity`, :mod:`pincal.measure`, :mod:`pincal.design` and
:mod:`pincal.identification` (never a later stage).
"""

from __future__ import annotations

from pincal.validation._cross_validation import (
    BlockScales,
    CrossValidation,
    compare,
    cross_validate,
    kfold,
    orientation_errors,
    position_errors,
)
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
from pincal.validation._held_out_gate import HeldOutEvidence, held_out_verdict
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
from pincal.validation._model_selection import (
    CandidateScore,
    Fitted,
    ModelSelection,
    fitted,
    select_model,
)
from pincal.validation._monte_carlo import MonteCarloStudy, monte_carlo
from pincal.validation._pose_errors import (
    PoseErrors,
    pose_errors,
)

__all__ = [
    "ORIENTATION_CONVENTION",
    "BlockScales",
    "CandidateScore",
    "CrossValidation",
    "CrossValidationBaseline",
    "CrossValidationSummary",
    "Fitted",
    "HeldOutEvidence",
    "HeldOutValidation",
    "MarkerErrors",
    "ModelSelection",
    "MonteCarloStudy",
    "OrientationErrors",
    "PointAccuracy",
    "PoseCharacteristics",
    "PoseErrors",
    "TestCube",
    "compare",
    "cross_validate",
    "fitted",
    "held_out_verdict",
    "iso_test_cube",
    "kfold",
    "marker_errors",
    "monte_carlo",
    "orientation_errors",
    "point_accuracy",
    "pose_characteristics",
    "pose_errors",
    "position_errors",
    "prediction_caveat",
    "select_model",
    "simulate_cycles",
    "validate_held_out",
]
