"""The problem a fit solves.

What is fitted: the residual model of a calibration problem (pose
files, instruments, sockets, marker sets), its data blocks and shared terms, the
configurations of the poses, the gauge and the fitted set.
"""

from __future__ import annotations

from pincal.identification.problem._data_blocks import DataBlock
from pincal.identification.problem._fit_set import (
    BaseRule,
    FitSet,
    JointBase,
    StructuralBase,
    WeakBound,
)
from pincal.identification.problem._gauge import constant_line, constant_std, null_motions
from pincal.identification.problem._identification_problem import IdentificationProblem
from pincal.identification.problem._instrument_problem import Dataset, InstrumentProblem
from pincal.identification.problem._marker_set import (
    MarkerSetProblem,
    StackedProblem,
    stacked_measurements,
)
from pincal.identification.problem._problem import TRIAL_FAILURES, CalibrationProblem
from pincal.identification.problem._recipes import InstrumentRecipe, PoseRecipe, mechanism_blob
from pincal.identification.problem._residual_model import RawResiduals, ResidualModel

__all__ = [
    "TRIAL_FAILURES",
    "BaseRule",
    "CalibrationProblem",
    "DataBlock",
    "Dataset",
    "FitSet",
    "IdentificationProblem",
    "InstrumentProblem",
    "InstrumentRecipe",
    "JointBase",
    "MarkerSetProblem",
    "PoseRecipe",
    "RawResiduals",
    "ResidualModel",
    "StackedProblem",
    "StructuralBase",
    "WeakBound",
    "constant_line",
    "constant_std",
    "mechanism_blob",
    "null_motions",
    "stacked_measurements",
]
