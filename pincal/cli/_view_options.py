"""The options of ``pincal view`` (poses, calibration, outputs, drawing) and their checks."""

from __future__ import annotations

import math
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

import click

__all__ = ["MAX_POSES", "check_view_request", "view_options"]

#: most poses drawn (ghost copies multiply the page size)
MAX_POSES = 200

_F = TypeVar("_F", bound=Callable[..., object])


def view_options(func: _F) -> _F:
    """Add the options of ``pincal view`` to ``func``, in the order ``--help`` lists."""
    options = [
        click.option(
            "--poses",
            "poses_file",
            type=click.Path(dir_okay=False, path_type=Path),
            help="Pose file (`pincal poses`), commands or measurement file, or a CSV naming "
            "the actuated joints (SI).",
        ),
        click.option(
            "--random",
            "n_random",
            type=click.IntRange(1, MAX_POSES),
            default=None,
            help="Draw N random workspace poses (default 5 when --poses is not given).",
        ),
        click.option("--seed", default=0, type=click.IntRange(min=0), show_default=True,
                     help="Seed of the random poses."),
        click.option(
            "--calibrated",
            type=click.Path(path_type=Path),
            help="Calibration directory (`pincal calibrate --out`): adds nominal → calibrated "
            "arrows.",
        ),
        click.option(
            "--html",
            "html_path",
            type=click.Path(dir_okay=False, path_type=Path),
            help="Write the self-contained HTML view here.",
        ),
        click.option(
            "--live",
            is_flag=True,
            help="Also open a live meshcat session, listening on the loopback interface only "
            "(127.0.0.1; see --host); it stops with pincal (Enter, Ctrl-C, SIGTERM, even "
            "SIGKILL).",
        ),
        click.option(
            "--host",
            default="127.0.0.1",
            show_default=True,
            help="IPv4 address the --live server listens on (0.0.0.0: every interface, "
            "reachable from other machines).",
        ),
        click.option(
            "--up",
            type=click.Choice(["auto", "+z", "-z", "+y", "-y", "+x", "-x"]),
            default="auto",
            show_default=True,
            help="World direction drawn upwards; auto reads the sidecar key view_up (default "
            "+z).",
        ),
        click.option("--ghosts/--no-ghosts", default=True, show_default=True,
                     help="Ghost copies."),
        click.option("--animate/--no-animate", default=True, show_default=True,
                     help="Animation."),
        click.option("--arrow-scale", type=float, default=None,
                     help="Arrow magnification (auto)."),
        click.option(
            "--allow-mesh-outside",
            is_flag=True,
            help="Also read meshes outside the model's directory (absolute paths, ../); the "
            "page embeds their bytes, so only for a URDF you trust.",
        ),
        click.option("--json", "as_json", is_flag=True,
                     help="Print a JSON summary instead of text."),
    ]
    for option in reversed(options):
        func = option(func)
    return func


def check_view_request(html_path: Path | None, live: bool, arrow_scale: float | None) -> None:
    """Refuse a view with no output, a live view without stdin, or a bad ``--arrow-scale``.

    Raises:
        click.UsageError: neither --html nor --live, or --live with stdin closed.
        click.BadParameter: --arrow-scale not a positive finite number.
    """
    if html_path is None and not live:
        raise click.UsageError("give --html FILE and/or --live")
    if live and (sys.stdin is None or sys.stdin.closed):
        raise click.UsageError(
            "--live waits for Enter on stdin to stop the viewer, but stdin is closed; run it "
            "with a terminal or a pipe on stdin, or write --html FILE instead"
        )
    if arrow_scale is not None and not (math.isfinite(arrow_scale) and arrow_scale > 0):
        raise click.BadParameter("must be a positive number", param_hint="--arrow-scale")
