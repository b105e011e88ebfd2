"""``pincal calibrate --link``: a marker table calibrated by the workflow, printed, written."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

import click

from pincal.cli._calibrate_text import result_json
from pincal.cli.common import model_source

if TYPE_CHECKING:  # imported in the calls: the CLI starts without the model stack
    from pincal.cli.common import ModelOptions
    from pincal.measure import MarkerSetup
    from pincal.model import Payload
    from pincal.workflow import MarkerSettings

__all__ = ["calibrate_markers", "check_marker_rows", "refuse_pose_options"]

#: the marker route's answer to the probes' blind spot (it takes no declared noise)
MARKER_REMEDY = ("the held-out prediction (printed below) judges a marker calibration; "
                 "validate it on another session (validate CAL --data OTHER)")  # fmt: skip


def refuse_pose_options(
    terms: tuple[str, ...] | list[str], load: Payload | None, model_opts: ModelOptions,
    noise: str | None, bootstrap: int,
) -> None:  # fmt: skip
    """Refuse the options of pose files on a marker table (``--link``).

    Raises:
        click.BadParameter: joint terms or a payload, ``--sidecar``/``--frame``,
            ``--noise``, ``--bootstrap``, or a joint locked at home.
    """
    if terms or load is not None:
        raise click.BadParameter(
            "joint-space terms are not yet fitted from marker tables (--link); use "
            "--model geometric there (and no --payload)",
            param_hint="--model",
        )
    if model_opts.sidecar or model_opts.frame:
        raise click.BadParameter(
            "a marker table (--link) is measured on LINK: --frame and --sidecar do not "
            "apply; give a sidecar file with `robot:` as MODEL instead",
            param_hint="--link",
        )
    if noise is not None:
        raise click.BadParameter(
            "a marker calibration (--link) estimates the noise from the residuals and is "
            "judged by held-out prediction; a declared noise applies to pose measurement "
            "files: drop --noise",
            param_hint="--noise",
        )
    if bootstrap:
        raise click.BadParameter(
            "a marker calibration (--link) is not bootstrapped yet; its σ are the linear "
            "ones (prior rows included)",
            param_hint="--bootstrap",
        )
    if "home" in model_opts.lock.values():
        raise click.BadParameter(
            "with --link, lock joints at a value (JOINT=VALUE [rad or m]), not at home",
            param_hint="--lock",
        )


def check_marker_rows(model: str, data: str, setup: MarkerSetup, preset: str, yes: bool) -> None:
    """Refuse a marker table of more rows than the pose route fits without ``--yes``.

    The rows are counted before the table is read; the chain is built (for the
    parameter count of the message's estimate) only for a table over the bound.

    Raises:
        InputLimitError: more than :data:`pincal.cli._limits.MAX_POSES` rows, no ``yes``.
    """
    from pincal.cli._limits import MAX_POSES, check_data_rows

    rows = check_data_rows(str(data), "--data", 0, True)
    if rows is None or rows <= MAX_POSES or yes:
        return
    from pincal.measure import marker_mechanism
    from pincal.sensitivity import parameters

    mech = marker_mechanism(model, setup)
    n = len(parameters(mech, preset)) if preset in mech.presets else len(mech.actuated) * 6
    check_data_rows(str(data), "--data", n, yes)


def calibrate_markers(
    model: str,
    data: str,
    setup: MarkerSetup,
    settings: MarkerSettings,
    out: str,
    as_json: bool,
    force: bool,
    *,
    yes: bool = False,
) -> None:
    """``calibrate --link``: run :func:`pincal.workflow.calibrate_markers`, gate, write.

    A table of more than :data:`pincal.cli._limits.MAX_POSES` rows is refused without
    ``yes`` (``--yes``), as on the pose route.
    """
    check_marker_rows(model, data, setup, settings.preset, yes)
    from pincal.cli._gate import apply_gate
    from pincal.io import CALIBRATED_URDF, write_calibration
    from pincal.report import calibration_text, marker_lines
    from pincal.workflow import calibrate_markers as run_markers
    from pincal.workflow import marker_doc

    run = run_markers(model, data, setup, settings, lambda line: click.echo(f"… {line}", err=True))
    for note in run.notes:
        click.echo(f"pincal: note: {note}", err=True)
    for warning in run.warnings:
        click.echo(f"pincal: warning: {warning}", err=True)
    quality = apply_gate(run.verdict, force)
    floor = quality.get("detection_floor")
    if isinstance(floor, dict) and floor.get("blind_spot"):  # the marker route has no --noise
        floor["blind_spot"] = run.verdict.blind_spot(MARKER_REMEDY)
    markers = marker_doc(run)
    doc = result_json(run.fit.result, str(data), CALIBRATED_URDF)
    doc["quality"] = quality
    doc["markers"] = markers
    report = calibration_text(run.fit.result, {"data": str(data), "quality": quality})
    report += "\n".join(marker_lines(run)) + "\n"
    cal = write_calibration(
        Path(out),
        run.fit.result,
        model_source=model_source(model),
        data_files=[data],
        annotations={"data": str(data), "quality": quality, "markers": markers},
        texts={"report.txt": report},
        nominal=run.fit.registration.mechanism,
    )
    if as_json:
        click.echo(json.dumps(doc))
    else:
        click.echo(report, nl=False)
        click.echo(f"wrote calibration directory {cal.path}/")
