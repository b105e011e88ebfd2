"""The executable-pose screens of `pincal poses`: their options.

The screens themselves are :func:`pincal.design.screen_candidates`, the reach screen's
compensation test :func:`pincal.workflow.compensation_test`; this module turns the
options into :class:`pincal.design.ScreenSettings` and the ``--reach-errors`` bounds.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, TypeVar

import click

from pincal.errors import OptionValueError

if TYPE_CHECKING:  # imported in the calls: the CLI starts without the design stack
    from pincal.design import ScreenSettings

_F = TypeVar("_F", bound=Callable[..., object])

__all__ = ["parse_reach_errors", "screen_options", "screen_settings"]


def screen_options(func: _F) -> _F:
    """The screen options of `pincal poses` (see docs/cli.md, "Executable poses")."""
    options = [
        click.option("--joint-margin", type=float, default=0.05, show_default=True,
                     help="Share of each actuator range kept free at both ends."),
        click.option("--singular-margin", type=float, default=0.1, show_default=True,
                     help="Least σ_min of the actuator → pose Jacobian, relative to its "
                     "median over the candidates (0: off)."),
        click.option("--obstacle", "obstacles", multiple=True, metavar="'X Y Z DX DY DZ'",
                     help="A box of the surroundings [mm]: centre and edge lengths in the "
                     "world frame (repeatable); poses touching it are removed."),
        click.option("--no-collisions", is_flag=True,
                     help="Do not screen self-collisions and obstacles."),
        click.option("--reach-errors", default="1,10", show_default=True,
                     help="MM,MRAD: parameter errors of the model each pose must compensate "
                     "on (no branch change, within limits); 'none': not screened."),
    ]  # fmt: skip
    for option in reversed(options):
        func = option(func)
    return func


def parse_reach_errors(text: str) -> tuple[float, float] | None:
    """``"1,10"`` → (1.0, 10.0) [mm, mrad]; ``"none"`` → None."""
    if text.strip().lower() == "none":
        return None
    parts = text.replace(" ", "").split(",")
    try:
        pair = tuple(float(p) for p in parts)
    except ValueError:
        pair = ()
    if len(pair) != 2 or not all(math.isfinite(v) for v in pair) or min(pair) < 0:
        raise OptionValueError(
            f"--reach-errors {text!r} must be MM,MRAD (two numbers >= 0, e.g. 1,10) or none"
        )
    return pair[0], pair[1]


def screen_settings(
    joint_margin: float, singular_margin: float, obstacles: tuple[str, ...], no_collisions: bool
) -> ScreenSettings:
    """:class:`pincal.design.ScreenSettings` from the options (errors name the option)."""
    from pincal.cli._limits import naming_option
    from pincal.design import ScreenSettings, parse_box

    with naming_option("--obstacle"):
        boxes = tuple(parse_box(t) for t in obstacles)
    return ScreenSettings(joint_margin, singular_margin, not no_collisions, boxes)
