"""``pincal calibrate --link``: a marker table's registration and joint fit, gated."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import click

from pincal.cli._calibrate_text import result_json
from pincal.cli.common import model_source

__all__ = ["calibrate_markers"]


def calibrate_markers(model, data, setup, preset, method, out, as_json, force, limits,
                       prior_spec, loss, profile) -> None:  # fmt: skip
    """``calibrate --link``: registration + joint fit from a marker table."""
    from pincal.cli._gate import apply_gate
    from pincal.cli._markers import marker_calibration
    from pincal.identification import check_quality
    from pincal.io import CALIBRATED_URDF, write_calibration
    from pincal.report import calibration_text, marker_lines

    run = marker_calibration(model, data, setup, preset, method, prior_spec, loss)
    fit, meas, markers = run.fit, run.meas, run.doc
    start = fit.registration.mechanism
    # the gate bounds registration unknowns (instrument frame, marker) apart from the
    # machine's parameters, and judges an estimated noise by the instrument profile
    if len(meas) == 1:
        verdict = check_quality(
            fit.result, meas[0], mech=start, limits=limits, instrument=profile
        )
    else:  # the gate's per-pose tests assume one measured frame: judged without them
        from pincal.identification import stacked_measurements

        verdict = check_quality(
            fit.result, stacked_measurements(meas), limits=limits, instrument=profile
        )
        verdict = _unconfirmed_outliers(verdict)
        markers["notes"].append(
            f"{len(meas)} markers: the quality gate judged the fit without its per-pose "
            "data and sensitivity tests and without the refit that confirms outliers (they "
            "assume one measured frame); outliers are reported as warnings"
        )
    quality = apply_gate(verdict, force)
    doc = result_json(fit.result, str(data), CALIBRATED_URDF)
    doc["quality"] = quality
    doc["markers"] = markers
    report = calibration_text(fit.result, {"data": str(data), "quality": quality})
    report += "\n".join(marker_lines(fit, run.setup, run.prior, run.prior_cv, method, loss,
                                     markers["notes"])) + "\n"  # fmt: skip
    cal = write_calibration(
        Path(out),
        fit.result,
        model_source=model_source(model),
        data_files=[data],
        annotations={"data": str(data), "quality": quality, "markers": markers},
        texts={"report.txt": report},
        nominal=start,
    )
    if as_json:
        click.echo(json.dumps(doc))
    else:
        click.echo(report, nl=False)
        click.echo(f"wrote calibration directory {cal.path}/")


def _unconfirmed_outliers(verdict):
    """Outlier refusals as warnings, for fits the gate cannot refit pose by pose.

    The gate confirms an outlier by refitting without it, which needs one measured frame;
    rows of several markers stacked are judged by their deleted residuals alone, so a
    flag is reported, with its poses named, but does not refuse.
    """
    from pincal.identification import QualityIssue

    issues = tuple(
        QualityIssue(i.kind, False, i.message + " (a warning: not confirmed by a refit)")
        if i.kind == "outliers" and i.refuse
        else i
        for i in verdict.issues
    )
    out = dataclasses.replace(verdict, issues=issues)
    return out if not out.passed else dataclasses.replace(out, cause="", cause_text="")
