"""The uncertainty of a fit.

How far to trust the numbers: the linearity check, the
parametric bootstrap (opt-in), the honest inflation of a covariance, intervals and the
uncertainty check of pose and instrument fits.
"""

from __future__ import annotations

from pincal.identification.uncertainty._bootstrap import Bootstrap, bootstrap_covariance
from pincal.identification.uncertainty._inflation import Inflation, inflated_covariance
from pincal.identification.uncertainty._instrument_uncertainty import instrument_uncertainty
from pincal.identification.uncertainty._intervals import Intervals, interval_quantiles
from pincal.identification.uncertainty._uncertainty import (
    KINDS,
    METHODS,
    UncertaintyCheck,
    check_uncertainty,
    covariance_kind,
    pose_recipe,
    pose_residual_model,
    prediction_covariance,
    result_intervals,
    with_uncertainty,
)

__all__ = [
    "KINDS",
    "METHODS",
    "Bootstrap",
    "Inflation",
    "Intervals",
    "UncertaintyCheck",
    "bootstrap_covariance",
    "check_uncertainty",
    "covariance_kind",
    "inflated_covariance",
    "instrument_uncertainty",
    "interval_quantiles",
    "pose_recipe",
    "pose_residual_model",
    "prediction_covariance",
    "result_intervals",
    "with_uncertainty",
]
