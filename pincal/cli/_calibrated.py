"""The calibrated mechanism a command is given: a calibration directory or, as in 0.1, a model.

A calibration directory (written by ``pincal calibrate``) is announced on stderr when read;
a model name or URDF stands for a calibrated model whose calibration was not recorded.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import click

from pincal.cli._joint_terms import calibration_terms
from pincal.cli.common import announce

if TYPE_CHECKING:  # imported in the calls: the CLI starts without the model stack
    from pincal.compensation import JointTermCorrection
    from pincal.model import Mechanism, Payload

__all__ = ["calibrated_mechanism", "calibrated_with_terms"]


def calibrated_with_terms(
    spec: str, payload: Payload | None = None, temperature: float | None = None
) -> tuple[Mechanism, str, JointTermCorrection | None, str]:
    """The calibrated mechanism of a calibration directory (or a model spec), with its terms.

    Args:
        spec: the calibration directory, or a model name / URDF.
        payload: the load at the targets (:class:`~pincal.model.Payload`, replacing the
            calibration's); only for a calibration with a compliance term.
        temperature: the machine temperature at the targets [°C]; only for a
            calibration with a thermal term.

    Returns:
        (mechanism, description of where it came from, the joint terms (None for a
        geometric calibration or a model), a line on them).

    Raises:
        click.BadParameter: a payload or a temperature the calibration cannot use.
    """
    from pincal.io import read_calibration
    from pincal.model import load_mechanism

    if Path(spec).is_dir() and not Path(spec, f"{Path(spec).name}.urdf").is_file():
        cal = read_calibration(spec)
        announce(cal)
        terms = calibration_terms(cal, payload, temperature)
        return cal.calibrated(), f"calibration {spec}", *terms
    if payload is not None:
        raise click.BadParameter(
            "a payload applies to a calibration directory with a compliance term",
            param_hint="--payload",
        )
    if temperature is not None:
        raise click.BadParameter(
            "a temperature applies to a calibration directory with a thermal term",
            param_hint="--temperature",
        )
    return load_mechanism(spec), f"model {spec}", None, ""


def calibrated_mechanism(spec: Path, nominal: Mechanism) -> Mechanism:
    """The calibrated mechanism of a calibration directory (a bare .urdf as in 0.1).

    Raises:
        ModelFileError: the calibration is not of ``nominal``'s model (other actuators,
            or a calibration directory of another model name).
    """
    from pincal.errors import ModelFileError
    from pincal.io import read_calibration
    from pincal.model import load_mechanism

    if spec.is_file() and spec.suffix.lower() == ".urdf":
        cal = load_mechanism(spec)
    else:
        directory = read_calibration(spec)
        announce(directory)
        cal = directory.calibrated()
    if tuple(cal.actuated) != tuple(nominal.actuated) or (
        spec.is_dir() and cal.name != nominal.name
    ):
        raise ModelFileError(
            f"calibration {str(spec)!r} is of model {cal.name!r} (actuators "
            f"{list(cal.actuated)}), not of {nominal.name!r}; give the calibrated model's "
            f"nominal MODEL"
        )
    return cal
