"""A marker calibration run again on other poses: what ``validate --cv`` refits.

:func:`rebuild` reads back what a marker calibration fitted (its set-up, the marker
mechanism, the data file, checked unchanged by its SHA-256);
:func:`replay_procedure` is the fit it ran — preset, method, the loss used, the prior
(``auto`` chosen again inside the poses given, so a held-out fold never chooses it) —
as measurements → calibrated mechanism.
"""

from __future__ import annotations

from typing import Any

from pincal.identification import Prior
from pincal.io import CalibrationDirectory, read_marker_sets
from pincal.measure import MarkerSetup, Measurements, marker_mechanism
from pincal.model import Mechanism
from pincal.workflow._marker_run import marker_procedure, registration_procedure
from pincal.workflow._prior_choice import nested_choice
from pincal.workflow._registrations import MarkerProcedure

__all__ = ["rebuild", "replay_procedure"]


def rebuild(cal: CalibrationDirectory) -> tuple[MarkerSetup, Mechanism, tuple[Measurements, ...]]:
    """(setup, mechanism, one measurement set per marker) of a marker calibration.

    Args:
        cal: a :class:`pincal.io.CalibrationDirectory` of a marker calibration.

    Raises:
        CalibrationDirectoryError: the calibration records no data file, or the file is
            gone or changed (:meth:`pincal.io.CalibrationDirectory.data_file`).
    """
    doc = cal.manifest.get("markers") or {}
    setup = MarkerSetup.from_dict(doc)
    mech = marker_mechanism(cal.model_source or cal.model, setup)
    with cal.reading_data_file() as path:  # the bytes parsed are the ones hashed
        return setup, mech, tuple(read_marker_sets(path, mech, setup))


def _recorded_prior(doc: dict[str, Any]) -> Prior | None:
    p = doc.get("prior")
    return None if p is None else Prior(p["length_mm"] * 1e-3, p["angle_mrad"] * 1e-3)


def replay_procedure(
    mech: Mechanism, setup: MarkerSetup, doc: dict[str, Any], registration_only: bool
) -> MarkerProcedure:
    """Measurements → calibrated mechanism, as the calibration of ``doc`` ran.

    ``doc`` is the calibration's ``markers`` record; ``registration_only`` gives the
    baseline (instrument frame + marker fitted, the robot nominal). The loss is the one
    the calibration used (``auto`` settled on all its poses); a prior chosen by ``auto``
    is chosen again on the poses given, with the calibration's K.
    """
    if registration_only:
        return registration_procedure(mech, setup)
    preset, method = doc.get("preset", "chain"), doc.get("method", "gauss-newton")
    procedure = marker_procedure(mech, setup, preset, method, doc.get("loss", "linear"))
    if doc.get("prior_spec") != "auto":
        return procedure(_recorded_prior(doc))
    return nested_choice(procedure, int(doc.get("cv_folds", 5)), int(doc.get("cv_seed", 0)))
