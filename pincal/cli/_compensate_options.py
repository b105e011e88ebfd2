"""The options of ``pincal compensate`` (targets or program, output, components, branch, load)."""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

import click

from pincal.cli._joint_terms import payload_option, temperature_option

__all__ = ["compensate_options"]

_F = TypeVar("_F", bound=Callable[..., object])


def compensate_options(func: _F) -> _F:
    """Add the options of ``pincal compensate`` to ``func``, in the order ``--help`` lists."""
    options = [
        click.option(
            "--targets",
            default=None,
            type=click.Path(dir_okay=False),
            help="Target poses file (pincal pose file, e.g. written by `pincal poses`).",
        ),
        click.option(
            "--program",
            default=None,
            type=click.Path(dir_okay=False),
            help="A G-code program of G0/G1 moves (X Y Z [A B C]) to rewrite into --out "
            "instead: each move's target compensated, every other line kept byte for byte.",
        ),
        click.option(
            "--out",
            required=True,
            type=click.Path(dir_okay=False),
            help="Commands CSV to write (with --program: the compensated program).",
        ),
        click.option(
            "--components",
            default=None,
            help="Pose components to reach, e.g. x,y,z (default: the model's measured "
            "components).",
        ),
        click.option(
            "--skip-unreachable",
            is_flag=True,
            help="Leave unreachable targets out (reported) instead of failing.",
        ),
        click.option(
            "--allow-branch-change",
            is_flag=True,
            help="Keep commands on another branch than their start (|Δq| > 0.5 rad / 50 mm "
            "from the nominal command, > π rad from another target's, or det of the actuator "
            "→ pose Jacobian changing sign); listed. Default: refused.",
        ),
        payload_option(
            "Load at the targets for a calibration with a compliance term (kg; centre of mass "
            "in m in the tool frame), e.g. 5,0,0,0.08. It replaces calibrate's --payload (a "
            "payload link of the URDF itself stays); default: the load the calibration was "
            "fitted with."
        ),
        temperature_option(
            "Machine temperature at the targets [°C] for a calibration with a thermal term "
            "(calibrate --model geometric+temperature); default: its reference, 20 °C."
        ),
        click.option("--json", "as_json", is_flag=True, help="Print a JSON summary on stdout."),
    ]
    for option in reversed(options):
        func = option(func)
    return func
