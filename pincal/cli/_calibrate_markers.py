"""``pincal calibrate --link``: a marker table calibrated by the workflow, printed, written."""

from __future__ import annotations

import json
from pathlib import Path

import click

from pincal.cli._calibrate_text import result_json
from pincal.cli.common import model_source

__all__ = ["calibrate_markers"]


def calibrate_markers(model, data, setup, settings, out, as_json, force) -> None:
    """``calibrate --link``: run :func:`pincal.workflow.calibrate_markers`, gate, write."""
    from pincal.cli._gate import apply_gate
    from pincal.io import CALIBRATED_URDF, write_calibration
    from pincal.report import calibration_text, marker_lines
    from pincal.workflow import calibrate_markers as run_markers

    run = run_markers(model, data, setup, settings, lambda line: click.echo(f"… {line}", err=True))
    for note in run.notes:
        click.echo(f"pincal: note: {note}", err=True)
    for warning in run.warnings:
        click.echo(f"pincal: warning: {warning}", err=True)
    quality = apply_gate(run.verdict, force)
    markers = run.doc()
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
