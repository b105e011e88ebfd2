"""Kinematics of many poses at once.

Kinematics of many poses at once: the batched tree walk, batched
closure Jacobians, block-structured Newton and the batched loop solver (numpy over poses).
"""

from __future__ import annotations

from pincal.model.batch._batch import (
    BatchKinematics,
    BatchModel,
    cross_cols,
    mm,
    mv,
    slice_kinematics,
)
from pincal.model.batch._batch_closures import closure_jacobian_batch
from pincal.model.batch._batch_fk import CHUNK, BatchLoopSolver
from pincal.model.batch._batch_newton import BatchNewton
from pincal.model.batch._batch_ops import cross3, jlog3_batch, log3_batch
from pincal.model.batch._block_solve import PassiveFactor
from pincal.model.batch._range_factor import RangeFactor

__all__ = [
    "CHUNK",
    "BatchKinematics",
    "BatchLoopSolver",
    "BatchModel",
    "BatchNewton",
    "PassiveFactor",
    "RangeFactor",
    "closure_jacobian_batch",
    "cross3",
    "cross_cols",
    "jlog3_batch",
    "log3_batch",
    "mm",
    "mv",
    "slice_kinematics",
]
