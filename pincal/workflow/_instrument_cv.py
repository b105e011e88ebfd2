"""The cross-validation of an instrument calibration (``validate --cv K``): held-out readings.

A calibration fitted on scalar instrument files (ballbar, sphere probe, planes, gauge…:
``# pincal instrument`` files) is cross-validated on its readings: the readings of every
file are split into K folds together (seeded); each fold refits the machine and the
instruments' constants (pivot, sphere centre, planes…) from the other folds as calibrate
ran it (:func:`pincal.identification.identify_instruments`, the same preset, method and
weak-direction bound), then predicts the held-out readings with that fit. The error is
the reading's residual, measured − predicted [m].

The baseline is the nominal machine with only the instruments' constants fitted on the
same training readings (the instrument registered, the machine left uncalibrated): what
the calibration must beat.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from pincal.errors import MeasurementFormatError, PincalError
from pincal.identification import GateLimits, InstrumentProblem, identify_instruments, solver
from pincal.io import CalibrationDirectory, file_kind, read_instrument_file
from pincal.measure import InstrumentData
from pincal.model import Mechanism, ParameterSet, parameters
from pincal.validation import CrossValidationBaseline, CrossValidationSummary, kfold

__all__ = ["instrument_cross_validation", "is_instrument_calibration"]


def is_instrument_calibration(cal: CalibrationDirectory) -> bool:
    """True when the calibration's first data file is a scalar instrument file."""
    if not cal.manifest.get("data_files"):
        return False
    return file_kind(cal.data_file()) == "instrument"


def _rows(data: InstrumentData, rows: np.ndarray) -> InstrumentData:
    """The readings ``rows`` of ``data``."""
    ids = None if data.ids is None else data.ids[rows]
    return replace(data, q_act=data.q_act[rows], values=data.values[rows], ids=ids)


def _predicted_errors(
    mech: Mechanism,
    params: ParameterSet,
    tests: Sequence[InstrumentData],
    labels: list[str],
    fitted: dict[str, float],
) -> np.ndarray:
    """Residuals [m] of the held-out readings ``tests`` under fitted values (by name).

    A constant the fit does not name (an id absent from its training readings) keeps
    its start value.
    """
    model = InstrumentProblem(mech, params, tests, labels)
    x = np.array([fitted.get(n, x0) for n, x0 in zip(model.names, model.x0, strict=True)])
    _, _, raws = model.residuals(x, False)
    return np.concatenate([np.asarray(r, dtype=float).ravel() for r in raws])


def _registered(
    mech: Mechanism, params: ParameterSet, train: Sequence[InstrumentData], labels: list[str]
) -> dict[str, float]:
    """The instruments' constants fitted with the machine nominal (Gauss–Newton), by name."""
    model = InstrumentProblem(mech, params, train, labels)
    entry = solver("gauss-newton")
    free = np.arange(model.n_machine, len(model.names))
    out = entry.solve(model, model.x0, free, entry.check_options(None), None)
    return dict(zip(model.names, (float(v) for v in out.x), strict=True))


def _split(sizes: list[int], fold: np.ndarray) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Per file, (training rows, held-out rows) of one fold of the stacked readings."""
    starts = np.cumsum([0, *sizes])
    train, test = [], []
    for i, n in enumerate(sizes):
        own = np.arange(starts[i], starts[i] + n)
        held = np.intersect1d(own, fold) - starts[i]
        test.append(held)
        train.append(np.setdiff1d(np.arange(n), held))
    return train, test


def instrument_cross_validation(
    cal: CalibrationDirectory, k: int, seed: int
) -> CrossValidationSummary:
    """The cross-validation of an instrument calibration (its held-out readings).

    Args:
        cal: a calibration of scalar instrument files (:func:`is_instrument_calibration`).
        k: folds of the readings of all files together.
        seed: the folds' seed (:func:`pincal.validation.kfold`).

    Returns:
        Held-out reading errors [m] of the calibration refitted per fold beside the
        nominal machine with the instruments registered; ``folds``: rows of the stacked
        readings (the files in the calibration's order) per fold.

    Raises:
        PincalError: a data file is gone or changed, is not a scalar instrument file,
            or a fold would leave a file without training readings.
    """
    nominal = cal.nominal()
    files = []
    datasets = []
    for i in range(len(cal.manifest.get("data_files") or [])):
        with cal.reading_data_file(i) as path:  # the bytes parsed are the ones hashed
            data = read_instrument_file(path, nominal)
        files.append(path)
        if not isinstance(data, InstrumentData):
            raise MeasurementFormatError(
                f"{path}: cross-validation of a calibration that mixes instrument kinds with "
                "sockets or pose files is not supported; cross-validate each file's "
                "calibration on its own"
            )
        datasets.append(data)
    stems = [path.stem for path in files]
    labels = stems if len(set(stems)) == len(stems) else [f"{s}{i}" for i, s in enumerate(stems)]
    params = parameters(nominal, cal.preset)
    method = str(cal.manifest.get("method") or "gauss-newton")
    limits = GateLimits()
    bound = (limits.max_length_change, limits.max_angle_change)
    sizes = [len(d.values) for d in datasets]
    folds = kfold(sum(sizes), k, seed)
    held, held0, fit_rms, fit0_rms = [], [], [], []
    for fold in folds:
        train_rows, test_rows = _split(sizes, fold)
        if any(r.size == 0 for r in train_rows):
            raise PincalError(
                f"with {k} folds a file is left without training readings ({sizes} readings "
                "per file); use fewer folds"
            )
        keep = [i for i, r in enumerate(test_rows) if r.size]
        train = [_rows(d, r) for d, r in zip(datasets, train_rows, strict=True)]
        tests = [_rows(datasets[i], test_rows[i]) for i in keep]
        out = identify_instruments(nominal, params, train, method=method, labels=labels,
                                   weak_bound=bound)  # fmt: skip
        fitted = dict(zip(out.names, (float(v) for v in out.values), strict=True))
        held.append(_predicted_errors(nominal, params, tests, [labels[i] for i in keep], fitted))
        fit_rms.append(_rms(_predicted_errors(nominal, params, train, labels, fitted)))
        registered = _registered(nominal, params, train, labels)
        held0.append(
            _predicted_errors(nominal, params, tests, [labels[i] for i in keep], registered)
        )
        fit0_rms.append(_rms(_predicted_errors(nominal, params, train, labels, registered)))
    e, e0 = np.concatenate(held), np.concatenate(held0)
    d = e0**2 - e**2
    gain = float(np.mean(d))
    se = float(np.std(d, ddof=1) / np.sqrt(d.size)) if d.size > 1 else float("inf")
    baseline = CrossValidationBaseline(
        "instruments only", _rms(e0), float(np.max(np.abs(e0))),
        _rms(np.array(fit0_rms)),
    )  # fmt: skip
    return CrossValidationSummary(
        k, seed, int(sum(sizes)), tuple(tuple(int(i) for i in rows) for rows in folds),
        float(cal.result.after.rms_position), _rms(e), float(np.max(np.abs(e))),
        _rms(np.array(fit_rms)), baseline, beats_baseline=gain > se, gain_mse=gain,
        gain_standard_error=se,
    )  # fmt: skip


def _rms(e: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(e))))
