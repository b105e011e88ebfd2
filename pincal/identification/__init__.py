"""Stage 5 — from measurements to parameters.

One :class:`IdentificationProblem` — one pose file, or several data sets mixing pose,
instrument and socket files — solved by a registered solver (``"gauss-newton"``,
``"lm"``, ``"qpso"``, ``"qpso-stepwise"``, ``"step-planned"``; the joint fit of several
data sets by the first two), gives one :class:`IdentificationResult` with covariances at
the Cramér–Rao bound: an :class:`IdentificationRecord` (what ``identification.json``
holds) with the live calibration. ``result_to_dict`` writes a record as that document,
``result_from_dict`` reads it back as a record.
"""

from __future__ import annotations

from pincal.identification._held import (
    HELD_AT_NOMINAL,
    held_at_nominal,
    held_summary,
    with_held,
)
from pincal.identification._identify import identify
from pincal.identification._instrument_design import (
    InstrumentIdentifiability,
    default_instrument,
    instrument_blocks,
    instrument_candidates,
    instrument_cramer_rao,
    instrument_identifiability,
)
from pincal.identification._instrument_identify import (
    InstrumentIdentification,
    identify_instruments,
)
from pincal.identification._marker_fit import (
    REGISTRATION_PRESET,
    MarkerFit,
    Prior,
    fit_markers,
    is_registration,
)
from pincal.identification._options import (
    LOSSES,
    GaussNewtonOptions,
    LMOptions,
    StepPlanningOptions,
)
from pincal.identification._verdict import GateLimits, QualityIssue, QualityVerdict
from pincal.identification._weighting import Weighting
from pincal.identification.gate import (
    INSTRUMENT_PROFILES,
    InstrumentProfile,
    check_instrument_data,
    check_measurements,
    check_quality,
    instrument_gate,
    instrument_profile,
    likely_cause,
    outlier_poses,
)
from pincal.identification.problem import (
    CalibrationProblem,
    IdentificationProblem,
    InstrumentProblem,
    MarkerSetProblem,
    StackedProblem,
    stacked_measurements,
)
from pincal.identification.results import (
    FORMAT_VERSION,
    IdentifiabilitySummary,
    IdentificationRecord,
    IdentificationResult,
    JointDetails,
    LocalSolverExtras,
    QPSOExtras,
    ResidualStats,
    SolverExtras,
    StepPlanningExtras,
    result_from_dict,
    result_to_dict,
)
from pincal.identification.solvers import (
    COST_MODELS,
    METHODS,
    SOLVERS,
    MarginalBound,
    QPSOOptions,
    QPSOResult,
    QPSOStage,
    QPSOStepwiseResult,
    Solver,
    qpso,
    qpso_stepwise,
    solver,
)
from pincal.identification.uncertainty import (
    KINDS as COVARIANCE_KINDS,
)
from pincal.identification.uncertainty import (
    METHODS as COVARIANCE_METHODS,
)
from pincal.identification.uncertainty import (
    Bootstrap,
    Inflation,
    Intervals,
    UncertaintyCheck,
    bootstrap_covariance,
    check_uncertainty,
    covariance_kind,
    inflated_covariance,
    instrument_uncertainty,
    interval_quantiles,
    pose_recipe,
    pose_residual_model,
    prediction_covariance,
    result_intervals,
    with_uncertainty,
)

__all__ = [
    "COST_MODELS",
    "COVARIANCE_KINDS",
    "COVARIANCE_METHODS",
    "FORMAT_VERSION",
    "HELD_AT_NOMINAL",
    "INSTRUMENT_PROFILES",
    "LOSSES",
    "METHODS",
    "REGISTRATION_PRESET",
    "SOLVERS",
    "Bootstrap",
    "CalibrationProblem",
    "GateLimits",
    "GaussNewtonOptions",
    "IdentifiabilitySummary",
    "IdentificationProblem",
    "IdentificationRecord",
    "IdentificationResult",
    "Inflation",
    "InstrumentIdentifiability",
    "InstrumentIdentification",
    "InstrumentProblem",
    "InstrumentProfile",
    "Intervals",
    "JointDetails",
    "LMOptions",
    "LocalSolverExtras",
    "MarginalBound",
    "MarkerFit",
    "MarkerSetProblem",
    "Prior",
    "QPSOExtras",
    "QPSOOptions",
    "QPSOResult",
    "QPSOStage",
    "QPSOStepwiseResult",
    "QualityIssue",
    "QualityVerdict",
    "ResidualStats",
    "Solver",
    "SolverExtras",
    "StackedProblem",
    "StepPlanningExtras",
    "StepPlanningOptions",
    "UncertaintyCheck",
    "Weighting",
    "bootstrap_covariance",
    "check_instrument_data",
    "check_measurements",
    "check_quality",
    "check_uncertainty",
    "covariance_kind",
    "default_instrument",
    "fit_markers",
    "held_at_nominal",
    "held_summary",
    "identify",
    "identify_instruments",
    "inflated_covariance",
    "instrument_blocks",
    "instrument_candidates",
    "instrument_cramer_rao",
    "instrument_gate",
    "instrument_identifiability",
    "instrument_profile",
    "instrument_uncertainty",
    "interval_quantiles",
    "is_registration",
    "likely_cause",
    "outlier_poses",
    "pose_recipe",
    "pose_residual_model",
    "prediction_covariance",
    "qpso",
    "qpso_stepwise",
    "result_from_dict",
    "result_intervals",
    "result_to_dict",
    "solver",
    "stacked_measurements",
    "with_held",
    "with_uncertainty",
]
