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

import json
from pathlib import Path

import click

from pincal.cli._calibrated import calibrated_mechanism
from pincal.cli._paths import guard_paths
from pincal.cli._view_draw import ViewOptions, draw_view, wait_live
from pincal.cli._view_options import MAX_POSES, check_view_request, view_options
from pincal.cli.common import ModelOptions, fail_cleanly, load_model, model_input, model_options


@click.command()
@click.argument("model")
@view_options
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
    from pincal.workflow import prediction_changes, view_poses

    check_view_request(html_path, live, arrow_scale)
    guard_paths(
        {"MODEL": model_input(model), "--poses": poses_file, "--calibrated": calibrated},
        {"--html": html_path},
    )
    mech = load_model(model, model_opts)
    poses = view_poses(mech, poses_file, n_random, seed, MAX_POSES)
    up_dir = str(mech.sidecar.view_up or "+z") if up == "auto" else up
    summary: dict = {"model": mech.name, "poses": len(poses), "up": up_dir}
    arrows: list[viz.Arrow] = []
    if calibrated is not None:
        changes = prediction_changes(mech, calibrated_mechanism(calibrated, mech), poses)
        ends = zip(changes.nominal, changes.calibrated, strict=True)
        arrows = [viz.Arrow(a, b, "#b0008c", f"pose {k}") for k, (a, b) in enumerate(ends)
                  if k not in changes.unreachable]  # fmt: skip
        if arrows:
            summary["max_prediction_change_mm"] = changes.largest_mm
        summary["unreachable_calibrated"] = list(changes.unreachable)
    options: ViewOptions = {"frame": mech.measured_frame, "ghosts": ghosts, "animate": animate,
                            "arrows": arrows, "arrow_scale": arrow_scale, "up": up_dir}  # fmt: skip
    title = f"{mech.name}: {len(poses)} poses" + (" — calibration changes" if arrows else "")
    html, session = draw_view(mech, poses.configurations, title, options, html_path, live,
                              host, allow_mesh_outside)  # fmt: skip
    if html is not None:
        summary["html"] = html
    if session is not None:
        summary["live_url"] = session.web_url
    if as_json:
        click.echo(json.dumps(summary))
    else:
        if html is not None:
            click.echo(f"wrote {html} ({len(poses)} poses of {mech.name})")
        if arrows:
            click.echo(f"largest nominal → calibrated prediction change: "
                       f"{summary['max_prediction_change_mm']:.4f} mm")  # fmt: skip
        if summary.get("unreachable_calibrated"):
            rows = ", ".join(str(k) for k in summary["unreachable_calibrated"])
            click.echo(f"note: the calibrated model cannot reach pose {rows} (0-based; its "
                       "loops do not close on home's branch there: beyond the calibrated "
                       "machine's workspace): drawn without an arrow")  # fmt: skip
    if session is not None:
        wait_live(session)
