"""The sensitivity stage's declared interface for the internals of later stages.

:mod:`pincal.sensitivity` (its ``__init__``) is what users and most stages import.
This module is the second, narrower door, used by :mod:`pincal.identification`: the
test of whether the batched Jacobian applies to a mechanism, batched prediction of
closed configurations, and the per-(mechanism, parameter set) plan that
:func:`pincal.sensitivity.pose_sensitivity` accepts to avoid recomputing it pose by
pose. Anything else in ``pincal.sensitivity._*`` may change without notice.
"""

from __future__ import annotations

from pincal.sensitivity._jacobian import jacobian_plan
from pincal.sensitivity.batch import batch_applies, predict_configurations

__all__ = [
    "batch_applies",
    "jacobian_plan",
    "predict_configurations",
]
