"""The result of a fit.

What a fit returns: the identification record and result, the
solver's outcome and progress, per-joint details, and the record's JSON form.
"""

from __future__ import annotations

from pincal.identification.results._joint_details import JointDetails
from pincal.identification.results._outcome import Progress, SolverOutcome
from pincal.identification.results._result import (
    IdentifiabilitySummary,
    IdentificationRecord,
    IdentificationResult,
    LocalSolverExtras,
    QPSOExtras,
    ResidualStats,
    SolverExtras,
    StepPlanningExtras,
)
from pincal.identification.results._result_io import FORMAT_VERSION, result_to_dict
from pincal.identification.results._result_read import result_from_dict

__all__ = [
    "FORMAT_VERSION",
    "IdentifiabilitySummary",
    "IdentificationRecord",
    "IdentificationResult",
    "JointDetails",
    "LocalSolverExtras",
    "Progress",
    "QPSOExtras",
    "ResidualStats",
    "SolverExtras",
    "SolverOutcome",
    "StepPlanningExtras",
    "result_from_dict",
    "result_to_dict",
]
