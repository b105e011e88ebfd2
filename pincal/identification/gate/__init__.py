"""The quality gate of a fit.

Whether the fit is believed: data checks, outliers and their refit,
misspecification probes, the residuals' autocorrelation, instrument profiles and the
quality verdict with its likely cause.
"""

from __future__ import annotations

from pincal.identification.gate._cause import likely_cause
from pincal.identification.gate._data_check import check_measurements
from pincal.identification.gate._instrument_gate import check_instrument_data, instrument_gate
from pincal.identification.gate._instrument_profiles import (
    INSTRUMENT_PROFILES,
    InstrumentProfile,
    instrument_profile,
)
from pincal.identification.gate._quality import check_quality, outlier_poses

__all__ = [
    "INSTRUMENT_PROFILES",
    "InstrumentProfile",
    "check_instrument_data",
    "check_measurements",
    "check_quality",
    "instrument_gate",
    "instrument_profile",
    "likely_cause",
    "outlier_poses",
]
