"""Instrument files calibrated as ``pincal calibrate --data FILE…`` does it.

Ballbar, touch-probe, socket-plate… readings (``# pincal instrument`` / ``# pincal
sockets`` files): :func:`calibrate_instrument_files` reads them (each file once), lets
the gate check their units (a refusal stops before the fit), fits the machine and the
instruments' constants together, judges the fit
(:func:`pincal.identification.instrument_gate`) and, when it passes, measures its σ
(:func:`pincal.identification.instrument_uncertainty`). Nothing is written.
"""

from __future__ import annotations

from pathlib import Path

from pincal.errors import DuplicateDataError, QualityGateError, UnidentifiableError
from pincal.identification import (
    GateLimits,
    check_instrument_data,
    identify_instruments,
    instrument_gate,
    instrument_uncertainty,
    with_uncertainty,
)
from pincal.io import read_instrument_file, sha256_file
from pincal.model import Mechanism, ParameterSet
from pincal.workflow._pose_run import PoseRun
from pincal.workflow._steps import Steps

__all__ = ["calibrate_instrument_files"]


def _once_each(files: list[str]) -> None:
    """Refuse one file's readings given twice (the same path, or a byte-for-byte copy).

    Fitted twice, every reading would count double: the σ understated by √2.

    Raises:
        DuplicateDataError: naming both --data files.
    """
    seen: dict[str, str] = {}
    for f in files:
        digest = sha256_file(f)
        if digest in seen:
            same = "is given twice" if seen[digest] == f else f"holds the same bytes as {f!r}"
            raise DuplicateDataError(
                f"--data {seen[digest]!r} {same}: its readings would be fitted twice, each "
                "counted double (the σ understated by √2); give each measurement file once"
            )
        seen[digest] = f


def calibrate_instrument_files(
    mech: Mechanism,
    params: ParameterSet,
    files: list[str],
    method: str,
    force: bool,
    limits: GateLimits,
    profile: str | None,
    bootstrap: int = 0,
    n_jobs: int = 1,
    steps: Steps | None = None,
) -> PoseRun:
    """Machine and instrument parameters from instrument files (ballbar, probe, sockets…).

    The readings' unit check refuses before the fit (unless ``force``); the fit is judged
    by :func:`pincal.identification.instrument_gate` (outliers confirmed by a refit) and,
    when it passes, its σ by :func:`pincal.identification.instrument_uncertainty`
    (the linear covariance plus the fit's measured second-order term); ``bootstrap`` > 0
    refits reported beside them (``n_jobs`` processes).

    Args:
        mech: the model.
        params: the machine's parameters to identify [m, rad].
        files: the instrument files, fitted together.
        method: the identification solver.
        force: refusals are recorded, not raised (``--force``).
        limits: the quality gate's limits.
        profile: the instrument profile judging an estimated noise, or None.
        bootstrap: refits reported beside the σ (0: none).
        n_jobs: processes of the refits (-1: every CPU).
        steps: progress callbacks (default: none); a direction nothing measured fixes
            is a ``steps.warn`` under ``force``.

    Returns:
        A :class:`PoseRun`: the machine part as an IdentificationResult with an honest
        covariance, the gate's verdict, the uncertainty check's summary (None when
        refused); ``noise`` None.

    Raises:
        QualityGateError: the readings' unit check refuses and ``force`` is False.
        DuplicateDataError: one file's readings given twice.
        UnidentifiableError: nothing measured fixes the length scale (sockets without a
            known distance), unless ``force``.
    """
    steps = steps or Steps()
    datasets = [read_instrument_file(f, mech) for f in files]  # each read bounded first
    _once_each(files)
    stems = [Path(f).stem for f in files]
    labels = stems if len(set(stems)) == len(stems) else None
    data = check_instrument_data(mech, datasets, stems, limits)
    if not data.passed and not force:
        raise QualityGateError(data.reason(), data)
    what = ", ".join(f"{len(d.q_act)} {d.kind}" for d in datasets)
    steps.say(f"identifying from {what} readings")
    with steps.iterations("identifying") as step:
        # a direction placed only beyond the gate's change bound (1σ) is held at nominal
        bound = (limits.max_length_change, limits.max_angle_change)
        out = identify_instruments(mech, params, datasets, method=method, labels=labels,
                                   progress=step, weak_bound=bound)  # fmt: skip
    for w in out.warnings:
        if not force:
            raise UnidentifiableError(f"{w} (--force writes the calibration anyway)")
        steps.warn(w)
    verdict = instrument_gate(out, data, limits, profile, mech=mech, datasets=datasets,
                              labels=labels)  # fmt: skip
    if not verdict.passed:
        notes = ("--bootstrap runs on a passed fit only; no refits ran",) if bootstrap else ()
        return PoseRun(out.result, verdict, None, None, notes)
    steps.say("checking the fit's curvature over its confidence region")
    with steps.counted("bootstrap refits") as step:
        check = instrument_uncertainty(out, mech, datasets, labels, draws=bootstrap,
                                       progress=step, n_jobs=n_jobs)  # fmt: skip
    return PoseRun(check.result, with_uncertainty(verdict, check), check.to_dict())
