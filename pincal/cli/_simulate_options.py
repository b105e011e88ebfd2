"""The options of ``pincal simulate`` and the parsing of their texts."""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

import click

from pincal.cli._kinds import InstrumentChoice
from pincal.cli._limits import ERROR_SIZE_RANGE, NOISE_RANGE, number_pair
from pincal.measure import DEFAULT_NOISE

_F = TypeVar("_F", bound=Callable[..., object])

__all__ = ["parse_errors", "parse_pair", "simulate_options"]


def parse_errors(spec: str) -> int | None:
    """The seed of ``--errors seed:N``, or None for ``none`` (click.BadParameter otherwise)."""
    if spec == "none":
        return None
    kind, _, seed = spec.partition(":")
    if kind != "seed" or not seed.strip().lstrip("-").isdigit():
        raise click.BadParameter(
            f"{spec!r}: use seed:N (random errors) or none", param_hint="--errors"
        )
    return int(seed)


def parse_pair(spec: str, option: str) -> tuple[float, float]:
    """Two finite numbers ≥ 0 (:func:`pincal.cli._limits.number_pair`)."""
    if option == "--error-size":
        return number_pair(spec, option, form="length_mm,angle_mrad", bounds=ERROR_SIZE_RANGE)
    return number_pair(spec, option, form="position_mm,orientation_mrad", bounds=NOISE_RANGE)


def simulate_options(func: _F) -> _F:
    """The options of ``pincal simulate`` (MODEL, --yes, --overwrite and the model's apart)."""
    options = [
        click.option(
            "--poses",
            "poses_file",
            type=click.Path(dir_okay=False),
            default=None,
            help="Poses file: its actuator columns are the commands (as `pincal poses` writes "
            "them); a file with target poses only is solved by the nominal IK. A commands or "
            "measurements file works too.",
        ),
        click.option(
            "--random",
            "n_random",
            type=click.IntRange(min=1),
            default=None,
            help="Number of random workspace poses instead of --poses.",
        ),
        click.option("--params", "preset", default=None,
                     help="Parameter preset (default: first preset)."),
        click.option(
            "--errors",
            default="seed:0",
            show_default=True,
            help="Geometric errors of the actual machine: seed:N (uniform draw) or none.",
        ),
        click.option(
            "--error-size",
            default="1,10",
            show_default=True,
            help="Error bounds 'length_mm,angle_mrad' (uniform ±).",
        ),
        click.option(
            "--noise",
            default=f"{DEFAULT_NOISE.position:g},{DEFAULT_NOISE.orientation:g}",
            show_default=True,
            help="Measurement noise 1σ 'position_mm,orientation_mrad' (the default of every "
            "command).",
        ),
        click.option("--seed", default=1, type=click.IntRange(min=0), show_default=True,
                     help="Seed of poses and noise."),
        click.option(
            "--length-unit",
            type=click.Choice(["m", "mm"]),
            default="m",
            show_default=True,
            help="Length unit of the written file (m round-trips exactly).",
        ),
        click.option(
            "--out",
            required=True,
            type=click.Path(dir_okay=False),
            help="Measurement CSV to write; the true errors go to <out>.truth.json.",
        ),
        click.option(
            "--instrument",
            type=InstrumentChoice(),
            default=None,
            help="Write one scalar reading per pose (ballbar, sphere probe, planes, gauge, or "
            "a registered kind) instead "
            "of poses, or (socket) the poses of a ball seated in two sockets 50 mm apart "
            "(half of --random each, the known distance declared); its noise is the position "
            "noise.",
        ),
        click.option(
            "--temperature",
            default=None,
            metavar="LOW,HIGH",
            help="Machine temperature range [°C], e.g. 18,28: each pose gets a uniform draw, "
            "written as the temperature_C column, and every actuated joint's length expands "
            "by --thermal (pose files only).",
        ),
        click.option(
            "--thermal",
            default=12e-6,
            show_default=True,
            type=click.FloatRange(-1e-3, 1e-3),
            help="True thermal expansion coefficient [1/K] with --temperature (steel: 12e-6).",
        ),
        click.option("--json", "as_json", is_flag=True, help="Print a JSON summary on stdout."),
    ]  # fmt: skip
    for option in reversed(options):
        func = option(func)
    return func
