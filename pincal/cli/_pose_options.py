"""The options of ``pincal poses`` and their checks."""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

import click

from pincal.cli._limits import NOISE_RANGE, check_number
from pincal.cli.common import jobs_option, scheduler_option
from pincal.measure import DEFAULT_NOISE

_F = TypeVar("_F", bound=Callable[..., object])

__all__ = ["check_noise", "jobs", "pose_options"]


def pose_options(func: _F) -> _F:
    """The design options of ``pincal poses`` (the screens' are :func:`screen_options`)."""
    options = [
        click.option("--count", default=18, show_default=True, help="Number of poses to select."),
        click.option(
            "--index",
            "index_name",
            type=click.Choice(["O1", "O2", "O3", "O4", "O5", "A"]),
            default="O1",
            show_default=True,
            help="Observability index to maximise.",
        ),
        click.option(
            "--candidates",
            "spec",
            default="auto",
            show_default=True,
            help="auto (grid:4, with random:500 added when the grid keeps fewer than 100 "
            "poses), grid:LEVELS (joint grid), random:COUNT or oa:LEVELS (orthogonal array); "
            "more than 200000 candidate poses or ~2 GB need --yes.",
        ),
        click.option("--preset", default=None,
                     help="Parameter preset (default: first, else full)."),
        click.option(
            "--scaling",
            type=click.Choice(["noise", "K", "none"]),
            default="noise",
            show_default=True,
            help="Row scaling: noise whitening, Jzg with --K, or unscaled SI.",
        ),
        click.option("--K", "K_mm", type=float, default=None,
                     help="Characteristic length [mm] (Jzg)."),
        click.option("--noise", nargs=2, type=float,
                     default=(DEFAULT_NOISE.position, DEFAULT_NOISE.orientation),
                     show_default=True,
                     help="Noise std: position [mm] orientation [mrad] (the default of every "
                     "command)."),
        click.option(
            "--method",
            type=click.Choice(["exchange", "detmax", "greedy"]),
            default="exchange",
            show_default=True,
        ),
        click.option(
            "--order",
            type=click.Choice(["travel", "selection"]),
            default="travel",
            show_default=True,
            help="Order of the poses in OUT: a short joint-space tour from home (nearest "
            "neighbour + 2-opt; 1 rad/s, 0.1 m/s) or the selection's order.",
        ),
        click.option("--restarts", default=3, show_default=True,
                     help="Random starts (best kept)."),
        click.option("--seed", default=0, type=click.IntRange(min=0), show_default=True,
                     help="Random seed."),
        click.option(
            "--out",
            default="poses.csv",
            show_default=True,
            help="Pose file to write (+ <stem>.commands.csv and <stem>.json beside it).",
        ),
        jobs_option("Processes evaluating the candidates (-1: every CPU); same poses for any "
                    "value."),
        scheduler_option("the candidates' evaluation (the same poses)"),
        click.option("--json", "as_json", is_flag=True, help="Print a JSON summary on stdout."),
    ]  # fmt: skip
    for option in reversed(options):
        func = option(func)
    return func


def check_noise(noise: tuple[float, float]) -> None:
    """``--noise``: two positive numbers within :data:`NOISE_RANGE` [mm, mrad].

    Raises:
        OptionValueError: one is not, naming which.
    """
    from pincal.errors import OptionValueError

    for value, name in zip(noise, ("--noise (position)", "--noise (orientation)"), strict=True):
        check_number(value, name, positive=True)
        if not NOISE_RANGE[0] <= value <= NOISE_RANGE[1]:
            raise OptionValueError(
                f"{name} {value:g} must be between {NOISE_RANGE[0]:g} and {NOISE_RANGE[1]:g} "
                "(mm, mrad)"
            )


def jobs(n_jobs: int) -> int:
    """``--jobs`` checked and clamped to the CPU count (more processes only compete)."""
    import os

    from pincal.errors import OptionValueError

    cpus = os.cpu_count() or 1
    if n_jobs == 0:
        raise OptionValueError(
            f"--jobs 0 is not valid; give a number of processes from 1 to {cpus} (the CPU "
            "count), or -1 for every CPU"
        )
    if n_jobs > cpus:
        click.echo(f"pincal: note: --jobs {n_jobs} is more than the {cpus} CPUs; using {cpus}",
                   err=True)  # fmt: skip
        return cpus
    return n_jobs
