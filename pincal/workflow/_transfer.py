"""A marker calibration carried to another session: is the robot's geometry still better?

A capture system recalibrated, moved, or a marker re-stuck between sessions leaves the
instrument frame and the marker unknown again, so a calibration cannot be checked on
another day's table with the frame it was fitted with. :func:`transfer_markers` asks
what a user of the calibrated robot would do there: register the instrument frame and
the marker(s) again on the new table, the robot's geometry held — as calibrated, and as
nominal (the registration-only baseline) — and compares how well each predicts poses
the registration did not see (K-fold: registered on K − 1 folds of the new table,
predicting the last). The registration's own unknowns are the same for both, so the
ratio of held-out RMS is the calibration's benefit carried to the new session.
"""

from __future__ import annotations

from pathlib import Path

from pincal.errors import PincalError
from pincal.identification import fit_markers
from pincal.io import CalibrationDirectory, read_marker_sets
from pincal.measure import MarkerSetup, Measurements
from pincal.model import Mechanism
from pincal.validation import HeldOutEvidence, cross_validate
from pincal.workflow._registrations import MarkerData, MarkerProcedure

__all__ = ["transfer_markers"]


def _registered(mech: Mechanism, setup: MarkerSetup) -> MarkerProcedure:
    def fit(meas: MarkerData) -> Mechanism:
        return fit_markers(mech, setup, meas, registration_only=True).calibrated

    return fit


def transfer_markers(
    cal: CalibrationDirectory, data: str | Path, k: int = 5, seed: int = 0
) -> HeldOutEvidence:
    """Held-out errors on another session's table, the registration refitted there.

    Args:
        cal: a :class:`pincal.io.CalibrationDirectory` of a marker calibration.
        data: the other session's marker table (the calibration's columns and set-up).
        k: folds of the new table.
        seed: the folds' seed (:func:`pincal.validation.kfold`).

    Returns:
        ``calibrated``: the calibrated robot, frame and marker registered per fold;
        ``baseline``: the nominal robot the same way (``registration only``).

    Raises:
        PincalError: not a marker calibration; errors of reading the table.
    """
    doc = cal.manifest.get("markers")
    if not doc:
        raise PincalError(f"{cal.path}: not a marker calibration; transfer applies to "
                          "marker tables (calibrate --link)")  # fmt: skip
    setup = MarkerSetup.from_dict(doc)
    nominal = cal.nominal()
    meas: tuple[Measurements, ...] = tuple(read_marker_sets(data, nominal, setup))
    calibrated = cross_validate(_registered(cal.calibrated(), setup), meas, k, seed)
    baseline = cross_validate(_registered(nominal, setup), meas, k, seed)
    return HeldOutEvidence(calibrated, baseline, "registration only")
