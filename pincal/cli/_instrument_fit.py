"""``pincal calibrate`` on instrument files: read, unit check, joint fit, the gate."""

from __future__ import annotations

from typing import TYPE_CHECKING

import click

if TYPE_CHECKING:  # imported in the calls: the CLI starts without the identification stack
    from pincal.identification import GateLimits, IdentificationResult, QualityVerdict
    from pincal.model import Mechanism, ParameterSet

__all__ = ["identify_instrument_files", "is_instrument_file"]


def is_instrument_file(path: str) -> bool:
    """True for an instrument file (``# pincal instrument`` / ``# pincal sockets``)."""
    from pincal.errors import PincalError
    from pincal.io import is_instrument_file as starts_as_instrument_file

    try:
        return starts_as_instrument_file(path)
    except PincalError:
        return False  # the measurement reader reports the problem


def _once_each(files: list[str]) -> None:
    """Refuse one file's readings given twice (the same path, or a byte-for-byte copy).

    Fitted twice, every reading would count double: the σ understated by √2.

    Raises:
        DuplicateDataError: naming both --data files.
    """
    from pincal.errors import DuplicateDataError
    from pincal.io import sha256_file

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


def identify_instrument_files(
    mech: Mechanism,
    params: ParameterSet,
    files: list[str],
    method: str,
    force: bool,
    limits: GateLimits,
    profile: str | None,
    bootstrap: int = 0,
    n_jobs: int = 1,
) -> tuple[QualityVerdict, IdentificationResult, dict[str, object] | None]:
    """Machine and instrument parameters from instrument files (ballbar, probe, sockets…).

    The readings' unit check refuses before the fit (unless ``force``); the fit is judged
    by :func:`pincal.identification.instrument_gate` (outliers confirmed by a refit) and,
    when it passes, its σ by :func:`pincal.identification.instrument_uncertainty`
    (the linear covariance plus the fit's measured second-order term); ``bootstrap`` > 0
    refits reported beside them (``n_jobs`` processes).

    Returns:
        (the gate's verdict, the machine part as an IdentificationResult with an honest
        covariance, the uncertainty check's JSON summary or None when refused).

    Raises:
        UnidentifiableError: nothing measured fixes the length scale (sockets without a
            known distance), unless ``force`` (then a warning on stderr).
    """
    from pathlib import Path

    from pincal.cli._gate import apply_gate
    from pincal.errors import UnidentifiableError
    from pincal.identification import check_instrument_data, identify_instruments, instrument_gate
    from pincal.io import read_instrument_file

    datasets = [read_instrument_file(f, mech) for f in files]  # each read bounded first
    _once_each(files)
    stems = [Path(f).stem for f in files]
    labels = stems if len(set(stems)) == len(stems) else None
    data = check_instrument_data(mech, datasets, stems, limits)
    apply_gate(data, force, before_fit=True)
    what = ", ".join(f"{len(d.q_act)} {d.kind}" for d in datasets)
    click.echo(f"… identifying from {what} readings", err=True)
    from pincal.cli._progress import iterations

    with iterations("identifying") as step:
        # a direction placed only beyond the gate's change bound (1σ) is held at nominal
        bound = (limits.max_length_change, limits.max_angle_change)
        out = identify_instruments(mech, params, datasets, method=method, labels=labels,
                                   progress=step, weak_bound=bound)  # fmt: skip
    for w in out.warnings:
        if not force:
            raise UnidentifiableError(f"{w} (--force writes the calibration anyway)")
        click.echo(f"pincal: warning: {w}", err=True)
    verdict = instrument_gate(out, data, limits, profile, mech=mech, datasets=datasets,
                              labels=labels)  # fmt: skip
    if not verdict.passed:
        if bootstrap:
            click.echo("pincal: note: --bootstrap runs on a passed fit only; no refits ran",
                       err=True)  # fmt: skip
        return verdict, out.result, None
    from pincal.identification import instrument_uncertainty, with_uncertainty

    click.echo("… checking the fit's curvature over its confidence region", err=True)
    from pincal.cli._progress import counted

    with counted("bootstrap refits") as step:
        check = instrument_uncertainty(out, mech, datasets, labels, draws=bootstrap,
                                       progress=step, n_jobs=n_jobs)  # fmt: skip
    return with_uncertainty(verdict, check), check.result, check.to_dict()
