"""A calibration checked on a held-out measurement file (``pincal validate --data``).

:func:`read_held_out` reads the file as calibrate read the calibration's data (a marker
table with the recorded marker set-up, its further markers apart; otherwise a
measurement file) and says whether the calibration was fitted on it;
:func:`validate_on_data` predicts it with the nominal and the calibrated model (the
latter moved by the calibration's joint terms when it has them), the further markers
too, and — for a marker table in an unknown instrument frame — carries the calibration
to the file's session (:func:`pincal.workflow.transfer_markers`). Nothing is printed or
written: the outcome is one :class:`DataValidation`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from pincal.compensation import JointTermCorrection
from pincal.errors import ConditionError
from pincal.identification import prediction_covariance
from pincal.io import (
    CalibrationDirectory,
    read_marker_sets,
    read_measurement_file,
    sha256_file,
)
from pincal.measure import MarkerSetup, Measurements
from pincal.model import Mechanism, ParameterSet
from pincal.sensitivity import parameters
from pincal.validation import (
    HeldOutEvidence,
    HeldOutValidation,
    MarkerErrors,
    marker_errors,
    validate_held_out,
)
from pincal.workflow._acceptance import held_out_machine
from pincal.workflow._transfer import transfer_markers

__all__ = ["DataValidation", "HeldOutData", "read_held_out", "validate_on_data"]

#: folds of the new session's table when a marker calibration is carried to it
TRANSFER_FOLDS = 5


@dataclass(frozen=True)
class HeldOutData:
    """A held-out measurement file, read as the calibration's data was.

    Attributes:
        path: the file.
        nominal: the calibration's nominal mechanism.
        params: the calibration's parameter set (its preset) on ``nominal``.
        meas: the measurements (SI: m, rad; the first marker of a marker table).
        more: a marker table's further markers: ((x, y, z) columns, measurements).
        warnings: the reader's warnings (a measurement file's) and, when ``pincal
            simulate`` wrote truths beside the file and the fit's data, a line when they
            describe other machines, in words.
        digest: the file's SHA-256 (hex).
        independent: False when the calibration was fitted on this file.
    """

    path: Path
    nominal: Mechanism
    params: ParameterSet
    meas: Measurements
    more: tuple[tuple[tuple[str, str, str], Measurements], ...]
    warnings: tuple[str, ...]
    digest: str
    independent: bool


@dataclass(frozen=True)
class DataValidation:
    """What :func:`validate_on_data` found.

    Attributes:
        data: the held-out file as read.
        validation: before (nominal) / after (calibrated) errors [m, rad], ISO 9283
            pose accuracy and the covariance's prediction.
        markers: the further markers' errors (empty with one marker).
        transfer: held-out errors with the registration refitted on the file (a marker
            calibration in an unknown instrument frame), else None.
        joint_terms: the line describing the joint terms predicted with ("" without).
    """

    data: HeldOutData
    validation: HeldOutValidation
    markers: list[MarkerErrors]
    transfer: HeldOutEvidence | None
    joint_terms: str

    def to_dict(self) -> dict[str, Any]:
        """The ``validate --json`` document after its ``calibration`` entry (mm, mrad)."""
        doc = {
            "data": str(self.data.path),
            "data_sha256": self.data.digest,
            "independent": self.data.independent,
            "joint_terms": self.joint_terms or None,
            **self.validation.to_dict(),
        }
        if self.markers:
            doc["more_markers"] = [m.to_dict() for m in self.markers]
        if self.transfer is not None:
            doc["transfer"] = self.transfer.to_dict()
        return doc


def read_held_out(
    cal: CalibrationDirectory,
    data: Path,
    check_rows: Callable[[int], object] | None = None,
) -> HeldOutData:
    """Read ``data`` as the calibration's data was read.

    Args:
        cal: the calibration.
        data: the held-out file (a marker table for a marker calibration).
        check_rows: called with the number of the calibration's parameters before the
            file is read (the caller's bound on the rows fitted).

    Raises:
        PincalError: errors of reading the file (see the readers).
    """
    nominal = cal.nominal()
    params = parameters(nominal, cal.preset)
    if check_rows is not None:
        check_rows(len(params))
    more: tuple[tuple[tuple[str, str, str], Measurements], ...] = ()
    warnings: tuple[str, ...] = ()
    if cal.manifest.get("markers"):  # a marker table, read as calibrate read it
        setup = MarkerSetup.from_dict(cal.manifest["markers"])
        meas, *rest = read_marker_sets(data, nominal, setup)
        more = tuple(zip(setup.more_columns, rest, strict=True))
    else:
        mf = read_measurement_file(data, nominal)
        warnings = tuple(mf.warnings)
        meas = mf.measurements
    digest = sha256_file(data)
    fitted = {d.get("sha256") for d in cal.manifest.get("data_files", []) or []}
    if digest not in fitted:  # a simulated file of another machine than the fit's data
        warnings += tuple(held_out_machine(cal, data))
    return HeldOutData(data, nominal, params, meas, more, warnings, digest, digest not in fitted)


def validate_on_data(
    cal: CalibrationDirectory,
    held: HeldOutData,
    terms: JointTermCorrection | None = None,
    terms_line: str = "",
    seed: int = 0,
) -> DataValidation:
    """Before / after errors of the calibration on a held-out file.

    Args:
        cal: the calibration.
        held: the file, from :func:`read_held_out`.
        terms: the calibration's joint terms (under the load of the measurements), or
            None for a geometric calibration: the calibrated model then predicts at the
            commands moved by their deflection.
        terms_line: the words describing ``terms`` (recorded in the JSON).
        seed: the folds' seed of the transfer to the file's session.

    Raises:
        ConditionError: the calibration has a thermal term but the file no
            ``temperature_C`` column.
    """
    meas = held.meas
    if terms is not None and "1/K" in terms.params.units and meas.temperature is None:
        raise ConditionError(
            f"{held.path} has no 'temperature_C' column, but calibration {str(cal.path)!r} has "
            f"a thermal term (calibrate --model geometric+temperature): it predicts each pose "
            f"at its own temperature, and at the reference 20 °C it would predict a machine at "
            f"20 °C, not the measured one; add the per-pose machine temperature [°C] as a "
            f"temperature_C column (as the calibration data had)"
        )
    result = cal.result
    markers_doc = cal.manifest.get("markers") or {}
    source = None if result.weighting is None else result.weighting.source
    propagated, kind = prediction_covariance(result.annotations, result.covariance, source)
    validation = validate_held_out(
        held.nominal,
        cal.calibrated(),
        meas,
        held.params,
        tuple(result.identified_names),
        result.covariance,
        meas.noise or cal.noise,
        tuple(markers_doc.get("held_weak") or ()),
        None if terms is None else meas.q_act + terms.deflection(meas.q_act, meas.conditions),
        kind,
        None if terms is None else terms.shift(meas.q_act, meas.conditions),
        _solution(result.names, result.full_values, held.params),
        propagated,
    )  # fmt: skip
    unseen = _unobserved(result.joint.gauge if result.joint is not None else ())
    if unseen and validation.predicted.get("withheld") is None:
        why = (f"the readings the calibration was fitted on do not observe all that these "
               f"poses measure ({'; '.join(unseen)}); those errors are the nominal model's "
               "and not in the covariance, so a prediction would be optimistic")  # fmt: skip
        predicted = {k: None for k in validation.predicted} | {
            "withheld": why, "covariance": validation.predicted.get("covariance")}
        validation = replace(validation, predicted=predicted)
    markers = marker_errors(held.nominal, cal.calibrated(), held.more) if held.more else []
    transfer = None
    if markers_doc.get("instrument_frame") == "unknown":
        transfer = transfer_markers(cal, held.path, TRANSFER_FOLDS, seed)
    return DataValidation(held, validation, markers, transfer, terms_line)


#: the starts of a joint fit's gauge lines naming what its data did not determine
_UNSEEN = ("not observed", "absorbed", "seen too weakly")


def _unobserved(gauge: tuple[str, ...] | list[str]) -> list[str]:
    """The gauge lines of a joint fit (instrument readings) naming what it left unseen."""
    return [line for line in gauge if line.startswith(_UNSEEN)]


def _solution(
    names: tuple[str, ...] | list[str], full_values: np.ndarray, params: ParameterSet
) -> np.ndarray | None:
    """(n,) the fit's values in the order of ``params`` [SI], or None.

    Its covariance was evaluated there; None when the record lacks a name of ``params``.
    """
    index = {n: k for k, n in enumerate(names)}
    if any(n not in index for n in params.names):
        return None
    return np.array([full_values[index[n]] for n in params.names], dtype=float)
