"""`pincal validate`'s outputs: the paths it may write, and the text it prints for --data."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import click

from pincal.cli._paths import guard_paths

if TYPE_CHECKING:
    from pincal.io import CalibrationDirectory
    from pincal.validation import CrossValidationSummary
    from pincal.workflow import DataValidation

__all__ = ["echo_data_validation", "guard_outputs"]


def guard_outputs(
    calibration: Path, data: Path | None, cv: bool, out: Path | None, folds_out: Path | None
) -> None:
    """Refuse --out / --folds-out paths that are inputs (the calibration's files, --data).

    ``cv``: the folds are read from the calibration's data file (an input too).
    """
    from pincal.cli._implicit_inputs import calibration_inputs
    from pincal.io import IDENTIFICATION_FILE, MANIFEST

    inputs: dict = {} if data is None else {"--data": data}
    inputs |= {f"CALIBRATION's {n}": calibration / n for n in (IDENTIFICATION_FILE, MANIFEST)}
    # its files, its nominal model's and (--cv) the data file the folds are read from
    inputs |= calibration_inputs(calibration, data_files=cv)
    guard_paths(inputs, {"--out": out, "--folds-out": folds_out})


def echo_data_validation(
    found: DataValidation, cal: CalibrationDirectory, cv: CrossValidationSummary | None
) -> None:
    """Print the validation on --data (and the --cv summary after it) as text."""
    from pincal.report import (
        cross_validation_text,
        marker_errors_text,
        transfer_text,
        validation_text,
    )

    data = str(found.data.path)
    if found.joint_terms:
        click.echo(f"calibrated model: geometry and {found.joint_terms} (joint = command + "
                   f"deflection; the nominal: commands)")  # fmt: skip
    click.echo(validation_text(found.validation, cal, data, found.data.independent), nl=False)
    click.echo(marker_errors_text(found.markers), nl=False)
    if found.transfer is not None:
        click.echo("(above: the instrument frame and marker as calibrated — the same "
                   "capture set-up only)")  # fmt: skip
        click.echo(transfer_text(found.transfer, data), nl=False)
    if cv is not None:
        click.echo(cross_validation_text(cv), nl=False)
