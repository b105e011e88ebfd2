"""`pincal view`: an offline HTML view (or a live meshcat session) of a mechanism's poses.

Poses file (read by :func:`pincal.io.read_pose_rows`): the pose file ``pincal poses``
writes, a command or measurement file, or a CSV file whose header names the actuated
joints of the model (any order; other columns are ignored), one pose per row, values
in SI units (m for prismatic, rad for revolute joints). Lines starting with ``#`` are
comments::

    # three poses of stewart_6ups
    leg1_slide,leg2_slide,leg3_slide,leg4_slide,leg5_slide,leg6_slide
    0.4869,0.4869,0.4869,0.4869,0.4869,0.4869
    0.50,0.47,0.50,0.47,0.50,0.47
"""

from __future__ import annotations

import contextlib
import json
import math
import signal
import sys
from collections.abc import Iterator
from pathlib import Path
from types import FrameType
from typing import TYPE_CHECKING, NoReturn, TypedDict

import click
import numpy as np

from pincal.cli._progress import counted
from pincal.cli.common import (
    ModelOptions,
    fail_cleanly,
    guard_paths,
    load_model,
    model_input,
    model_options,
)
from pincal.errors import ModelFileError
from pincal.io import read_pose_rows

if TYPE_CHECKING:
    from pincal.model import Mechanism
    from pincal.viz import Arrow

#: most poses drawn (ghost copies multiply the page size)
MAX_POSES = 200


class _ViewOptions(TypedDict):
    """Keywords shared by :func:`pincal.viz.static_html` and :func:`pincal.viz.live`."""

    frame: str | None
    ghosts: bool
    animate: bool
    arrows: list[Arrow]
    arrow_scale: float | None
    up: str


def _calibrated_mechanism(spec: Path) -> Mechanism:
    """The calibrated mechanism of a calibration directory (a bare .urdf as in 0.1)."""
    from pincal.cli.common import announce
    from pincal.io import read_calibration
    from pincal.model import load_mechanism

    if spec.is_file() and spec.suffix.lower() == ".urdf":
        return load_mechanism(spec)
    cal = read_calibration(spec)
    announce(cal)
    return cal.calibrated()


def _urdf_for_viz(mech: Mechanism) -> str | Path:
    """What viz draws from: the URDF file, or the URDF text of a model from MJCF."""
    src = mech.source
    if src is not None and Path(src).suffix.lower() == ".urdf" and Path(src).is_file():
        return Path(src)
    return mech.urdf_xml


@click.command()
@click.argument("model")
@click.option(
    "--poses",
    "poses_file",
    type=click.Path(dir_okay=False, path_type=Path),
    help="Pose file (`pincal poses`), commands or measurement file, or a CSV naming the "
    "actuated joints (SI).",
)
@click.option(
    "--random",
    "n_random",
    type=click.IntRange(1, MAX_POSES),
    default=None,
    help="Draw N random workspace poses (default 5 when --poses is not given).",
)
@click.option("--seed", default=0, type=click.IntRange(min=0), show_default=True,
              help="Seed of the random poses.")  # fmt: skip
@click.option(
    "--calibrated",
    type=click.Path(path_type=Path),
    help="Calibration directory (`pincal calibrate --out`): adds nominal → calibrated arrows.",
)
@click.option(
    "--html",
    "html_path",
    type=click.Path(dir_okay=False, path_type=Path),
    help="Write the self-contained HTML view here.",
)
@click.option(
    "--live",
    is_flag=True,
    help="Also open a live meshcat session, listening on the loopback interface only "
    "(127.0.0.1; see --host); it stops with pincal (Enter, Ctrl-C, SIGTERM, even SIGKILL).",
)
@click.option(
    "--host",
    default="127.0.0.1",
    show_default=True,
    help="IPv4 address the --live server listens on (0.0.0.0: every interface, reachable "
    "from other machines).",
)
@click.option(
    "--up",
    type=click.Choice(["auto", "+z", "-z", "+y", "-y", "+x", "-x"]),
    default="auto",
    show_default=True,
    help="World direction drawn upwards; auto reads the sidecar key view_up (default +z).",
)
@click.option("--ghosts/--no-ghosts", default=True, show_default=True, help="Ghost copies.")
@click.option("--animate/--no-animate", default=True, show_default=True, help="Animation.")
@click.option("--arrow-scale", type=float, default=None, help="Arrow magnification (auto).")
@click.option(
    "--allow-mesh-outside",
    is_flag=True,
    help="Also read meshes outside the model's directory (absolute paths, ../); the page "
    "embeds their bytes, so only for a URDF you trust.",
)
@click.option("--json", "as_json", is_flag=True, help="Print a JSON summary instead of text.")
@model_options
@fail_cleanly
def view(
    model: str,
    poses_file: Path | None,
    n_random: int | None,
    seed: int,
    calibrated: Path | None,
    html_path: Path | None,
    live: bool,
    host: str,
    up: str,
    ghosts: bool,
    animate: bool,
    arrow_scale: float | None,
    allow_mesh_outside: bool,
    as_json: bool,
    model_opts: ModelOptions,
) -> None:
    """Show MODEL at measurement poses: an offline HTML page (no server, no network).

    Each pose is a semi-transparent ghost in its own colour, an opaque copy animates
    through them, and the measured frame's axes are drawn at every pose. With
    --calibrated, arrows go from the nominal to the calibrated model's predicted
    measured-frame position at each pose, magnified by the factor in the legend.

    --poses reads the pose file `pincal poses` writes (its actuator columns, or the
    nominal inverse kinematics of its poses), a commands or measurement file, or a
    plain CSV whose header names the actuated joints (SI units; other columns
    ignored; '#' starts a comment line):

    \b
      leg1_slide,leg2_slide,leg3_slide,leg4_slide,leg5_slide,leg6_slide
      0.4869,0.4869,0.4869,0.4869,0.4869,0.4869

    \b
    Examples:
      pincal view stewart_6ups --random 6 --html poses.html
      pincal view hexaslide_6pus --poses poses.csv --calibrated cal/ --html errors.html
      pincal view pkm5 --random 4 --live
    """
    from pincal import viz
    from pincal.model import sample_actuators

    if html_path is None and not live:
        raise click.UsageError("give --html FILE and/or --live")
    if live and (sys.stdin is None or sys.stdin.closed):
        raise click.UsageError(
            "--live waits for Enter on stdin to stop the viewer, but stdin is closed; run it "
            "with a terminal or a pipe on stdin, or write --html FILE instead"
        )
    if arrow_scale is not None and not (math.isfinite(arrow_scale) and arrow_scale > 0):
        raise click.BadParameter("must be a positive number", param_hint="--arrow-scale")
    guard_paths(
        {"MODEL": model_input(model), "--poses": poses_file, "--calibrated": calibrated},
        {"--html": html_path},
    )
    mech = load_model(model, model_opts)
    if poses_file is not None:
        rows = read_pose_rows(poses_file, mech, MAX_POSES)
        if n_random:
            rows = np.vstack([rows, sample_actuators(mech, n_random, np.random.default_rng(seed))])
    else:
        rows = sample_actuators(mech, n_random or 5, np.random.default_rng(seed))
    qs = mech.configurations(rows)

    arrows: list[Arrow] = []
    if calibrated is not None:
        cal = _calibrated_mechanism(calibrated)
        if tuple(cal.actuated) != tuple(mech.actuated) or (
            calibrated.is_dir() and cal.name != mech.name
        ):
            raise ModelFileError(
                f"calibration {str(calibrated)!r} is of model {cal.name!r} (actuators "
                f"{list(cal.actuated)}), not of {mech.name!r}; give the calibrated model's "
                f"nominal MODEL"
            )
        for k, row in enumerate(rows):
            p_nominal = np.array(mech.forward(row, qs[k]).translation)
            p_calibrated = np.array(cal.forward(row, qs[k]).translation)
            arrows.append(viz.Arrow(p_nominal, p_calibrated, "#b0008c", f"pose {k}"))

    up_dir = str(mech.sidecar.view_up or "+z") if up == "auto" else up
    options: _ViewOptions = {
        "frame": mech.measured_frame,
        "ghosts": ghosts,
        "animate": animate,
        "arrows": arrows,
        "arrow_scale": arrow_scale,
        "up": up_dir,
    }
    summary: dict = {"model": mech.name, "poses": len(rows), "up": up_dir}
    if arrows:
        lengths = [float(np.linalg.norm(a.end - a.start)) * 1e3 for a in arrows]
        summary["max_prediction_change_mm"] = max(lengths)
    source = _urdf_for_viz(mech)
    with viz.allow_mesh_outside(allow_mesh_outside):  # meshes are read (and embedded) here
        if html_path is not None:
            title = f"{mech.name}: {len(rows)} poses" + (" — calibration changes" if arrows else "")
            with counted("scene", unit="pose") as step:
                page = viz.static_html(
                    mech.model, source, list(qs), title=title, progress=step, **options
                )
            summary["html"] = str(viz.write_html(html_path, page))
        session = None
        if live:
            with counted("live scene", unit="pose") as step:
                session = viz.live(
                    mech.model, source, list(qs), host=host, progress=step, **options
                )
    if session is not None:
        summary["live_url"] = session.web_url
    if as_json:
        click.echo(json.dumps(summary))
    else:
        if "html" in summary:
            click.echo(f"wrote {summary['html']} ({len(rows)} poses of {mech.name})")
        if arrows:
            click.echo(
                f"largest nominal → calibrated prediction change: "
                f"{summary['max_prediction_change_mm']:.4f} mm"
            )
    if session is not None:
        click.echo(f"meshcat viewer at {session.web_url} — press Enter to stop", err=True)
        try:
            with _exit_on_signals():
                sys.stdin.readline()
        finally:
            session.close()


@contextlib.contextmanager
def _exit_on_signals() -> Iterator[None]:
    """Turn SIGTERM / SIGHUP into SystemExit, so ``finally`` stops the live server."""

    def leave(signum: int, _frame: FrameType | None) -> NoReturn:
        raise SystemExit(128 + signum)

    wanted = [signal.SIGTERM] + ([signal.SIGHUP] if hasattr(signal, "SIGHUP") else [])
    old = {s: signal.signal(s, leave) for s in wanted}
    try:
        yield
    finally:
        for s, handler in old.items():
            signal.signal(s, handler)
