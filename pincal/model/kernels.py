"""The model stage's declared interface for the numerical internals of later stages.

:mod:`pincal.model` (its ``__init__``) is what users and most stages import. This
module is the second, narrower door: the batched kinematics kernels, loop-closure
factorisations and small helpers that :mod:`pincal.sensitivity` (batched Jacobians
and predictions), :mod:`pincal.identification` (batched residuals), :mod:`pincal.design`
(sampling ranges) and :mod:`pincal.viz` (Pinocchio diagnostics) build on. Exactly
what they use is re-exported here; anything else in ``pincal.model._*`` may change
without notice. Shapes follow the batch convention: a leading axis of N poses.
"""

from __future__ import annotations

from pincal.model.batch import (
    CHUNK,
    PassiveFactor,
    RangeFactor,
    closure_jacobian_batch,
    cross3,
    cross_cols,
    jlog3_batch,
    log3_batch,
    mm,
    mv,
    slice_kinematics,
)
from pincal.model.files import captured_stderr, measured_jacobian, measurement_residual
from pincal.model.reach import joint_ranges

__all__ = [
    "CHUNK",
    "PassiveFactor",
    "RangeFactor",
    "captured_stderr",
    "closure_jacobian_batch",
    "cross3",
    "cross_cols",
    "jlog3_batch",
    "joint_ranges",
    "log3_batch",
    "measured_jacobian",
    "measurement_residual",
    "mm",
    "mv",
    "slice_kinematics",
]
