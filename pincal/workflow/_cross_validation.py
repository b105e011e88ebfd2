"""K-fold cross-validation of a calibration, as calibrate ran it (``validate --cv K``).

Every fold is refitted from scratch on the other folds — for a marker calibration the
closed-form registration too, and ``--prior auto`` chooses its strength again inside the
fold — so nothing of a held-out pose reaches its prediction. The baseline is the
registration-only model (instrument frame + marker: the robot left uncalibrated) for a
marker calibration, the nominal model otherwise. With orientation measured (a 6-D
marker body, a pose file) the held-out rotation error angles are reported beside the
positions; for a marker body the verdict weighs both, each whitened by its noise σ. A marker
calibration's own cross-validation (recorded by calibrate) is reused for the same K and
seed unless ``refit``. A ball-in-socket calibration is cross-validated on its held-out
seatings (see ``_socket_cv``), one of scalar instrument files on its held-out readings
(see ``_instrument_cv``). The outcome is a
:class:`pincal.validation.CrossValidationSummary`; :func:`pincal.report.cross_validation_text`
renders it, :func:`fold_table` lists its folds.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from pincal.errors import PincalError
from pincal.identification import LMOptions, identify
from pincal.io import CalibrationDirectory, read_measurement_file
from pincal.measure import Measurements
from pincal.model import Mechanism
from pincal.sensitivity import parameters
from pincal.validation import (
    CrossValidation,
    CrossValidationBaseline,
    CrossValidationSummary,
    OrientationErrors,
    compare,
    cross_validate,
)
from pincal.workflow._instrument_cv import instrument_cross_validation, is_instrument_calibration
from pincal.workflow._marker_replay import rebuild, replay_procedure
from pincal.workflow._socket_cv import is_socket_calibration, socket_cross_validation

__all__ = ["cross_validate_calibration", "fold_table"]

#: the poses a cross-validated fit takes: one set, or one per marker (same rows)
_Poses = Measurements | tuple[Measurements, ...]


def _pose_fit(
    cal: CalibrationDirectory,
) -> tuple[Measurements, Callable[[_Poses], Mechanism], Callable[[_Poses], Mechanism]]:
    """(measurements, fit, baseline fit) of a pose-file calibration, as calibrate ran it.

    Replayed: the preset, the method, the robust loss and a declared noise (from the
    calibration's weighting record).
    """
    nominal = cal.nominal()
    with cal.reading_data_file() as path:  # the bytes parsed are the ones hashed
        meas = read_measurement_file(path, nominal).measurements
    params = parameters(nominal, cal.preset)
    if params.joint_terms.size:
        raise PincalError(
            f"{cal.path}: validate --cv predicts with the calibrated URDF, which does not carry "
            f"the joint terms of {cal.preset!r}; cross-validate them with `pincal select-model`"
        )
    method = str(cal.manifest.get("method") or "gauss-newton")
    w = cal.result.weighting
    loss = "linear" if w is None else w.loss
    options = LMOptions(loss=loss) if loss != "linear" else None
    noise = None
    if w is not None and w.source == "declared":  # --noise or the file's header
        noise = {"position": w.position_std * 1e3, "orientation": w.orientation_std * 1e3}

    def fit(m: _Poses) -> Mechanism:
        return identify(
            nominal, params, m, method, noise=noise, options=options
        ).calibrated_mechanism

    return meas, fit, lambda m: nominal


def _recorded(
    markers: dict, k: int, seed: int
) -> tuple[CrossValidation, CrossValidation] | None:
    """(calibrated, baseline) cross-validations calibrate recorded on these folds, or None."""
    rec = markers.get("cross_validation")
    if not rec or rec.get("folds") != k or rec.get("seed") != seed:
        return None
    return CrossValidation.from_record(rec["calibrated"]), CrossValidation.from_record(
        rec["baseline"]
    )


def cross_validate_calibration(
    cal: CalibrationDirectory, k: int, seed: int, refit: bool = False
) -> CrossValidationSummary:
    """The cross-validation of ``validate --cv`` (its ``to_dict()``: the ``cv`` JSON).

    A marker calibration records the cross-validation its gate ran (the same procedure,
    folds from the same K and seed): that one is reused unless ``refit``, after
    :func:`pincal.workflow.rebuild` has checked the data file unchanged.

    Args:
        cal: the calibration (marker table, pose file, ball-in-socket or instrument files).
        k: number of folds (2 ≤ k ≤ poses).
        seed: the folds' seed (:func:`pincal.validation.kfold`).
        refit: fit the folds again even when the calibration recorded them.

    Returns:
        Held-out RMS / max [m] (and rotation angles [rad] when measured) of the
        calibration and of its baseline; ``folds``: the pose rows of each fold.

    Raises:
        PincalError: the data file is gone or changed, or the fit cannot be replayed.
    """
    if is_socket_calibration(cal):
        return socket_cross_validation(cal, k, seed)
    if is_instrument_calibration(cal):
        return instrument_cross_validation(cal, k, seed)
    markers = cal.manifest.get("markers")
    recorded = None
    meas: _Poses
    if markers:
        setup, mech, meas = rebuild(cal)
        fit = replay_procedure(mech, setup, markers, registration_only=False)
        base = replay_procedure(mech, setup, markers, registration_only=True)
        baseline_name = "registration only"
        recorded = None if refit else _recorded(markers, k, seed)
    else:
        meas, fit, base = _pose_fit(cal)
        baseline_name = "nominal model"
    poses = len(meas[0]) if isinstance(meas, tuple) else len(meas)  # one set per marker
    if recorded is not None:
        full, ref = recorded
    else:
        full = cross_validate(fit, meas, k, seed)
        ref = cross_validate(base, meas, k, seed)
    gain, se, beats = compare(full, ref)
    # a 6-D marker body: both blocks, whitened (pose files: positions, as before)
    scales = full.fit_scales() if markers else None
    whitened = None
    if scales is not None:
        wg, wse, beats = compare(full, ref, scales)
        whitened = (wg, wse)
    fit_angle = float(cal.result.after.rms_orientation)
    return CrossValidationSummary(
        k, seed, poses, tuple(tuple(int(i) for i in rows) for rows in full.folds),
        float(cal.result.after.rms_position), full.rms, full.max, _fold_fit(full),
        CrossValidationBaseline(baseline_name, ref.rms, ref.max, _fold_fit(ref),
                                orientation=_angles(ref)),
        bool(beats), gain_mse=gain, gain_standard_error=se,
        orientation=_angles(full, fit_angle), whitened_gain=whitened,
        recorded=recorded is not None,
    )  # fmt: skip


def _angles(cv: CrossValidation, fit_rms: float | None = None) -> OrientationErrors | None:
    """The rotation errors of a cross-validation [rad], None without orientation."""
    if cv.held_out_orientation is None:
        return None
    rms, worst, per_fold = cv.orientation_rms, cv.orientation_max, cv.fit_orientation_rms
    assert rms is not None and worst is not None and per_fold is not None  # set together
    fold_fit = float(np.sqrt(np.mean(per_fold**2)))
    return OrientationErrors(rms, worst, fold_fit, fit_rms)


def _fold_fit(cv: CrossValidation) -> float:
    """RMS over the folds of each fold fit's RMS on its own poses [m]."""
    return float(np.sqrt(np.mean(cv.fit_rms**2)))


def fold_table(folds: Sequence[Sequence[int]], poses: int) -> str:
    """The ``--folds-out`` CSV: one line ``pose,fold`` per pose row (0-based).

    Args:
        folds: the pose rows of each fold (``CrossValidationSummary.folds``).
        poses: number of poses; every row is in one fold.
    """
    fold_of = np.empty(poses, dtype=int)
    for j, rows in enumerate(folds):
        fold_of[np.asarray(rows, dtype=int)] = j
    return "pose,fold\n" + "".join(f"{i},{f}\n" for i, f in enumerate(fold_of))
