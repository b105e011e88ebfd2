"""`pincal validate`: errors of a calibration on held-out measurements."""

from __future__ import annotations

import json
from pathlib import Path

import click

from pincal.cli._joint_terms import calibration_terms, payload_option, read_payload
from pincal.cli._limits import check_data_rows, yes_option
from pincal.cli._validate_out import echo_data_validation, guard_outputs
from pincal.cli.common import announce, calibration_summary, fail_cleanly


@click.command()
@click.argument("calibration", type=click.Path(path_type=Path))
@click.option("--data", default=None, type=click.Path(dir_okay=False, path_type=Path),
              help="Held-out measurement file (not used for fitting); required without --cv.")
@click.option("--cv", "cv_folds", type=click.IntRange(2, 1000), default=None, metavar="K",
              help="K-fold cross-validation over the fitted poses: each fold refitted "
              "as calibrate ran, held-out RMS/max beside the registration-only model.")
@click.option("--seed", "cv_seed", type=int, default=0, show_default=True,
              help="Seed of the --cv folds.")
@click.option("--refit", is_flag=True,
              help="With --cv: fit the folds again even when the calibration recorded "
              "this cross-validation (a marker calibration's gate, same K and seed).")
@click.option("--folds-out", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="Write the --cv folds (pose row, fold) as CSV.")
@click.option("--json", "as_json", is_flag=True, help="Print the full validation as JSON.")
@yes_option
@click.option("--out", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="Also write the full validation JSON to this file (for "
              "`pincal report --validation`).")
@payload_option("The load during the --data measurements (kg; centre of mass in m in the "
                "tool frame), replacing the calibration's, for its compliance terms.")
@fail_cleanly
def validate(
    calibration: Path, data: Path | None, cv_folds: int | None, cv_seed: int, refit: bool,
    folds_out: Path | None, as_json: bool, yes: bool, out: Path | None, payload: str | None,
) -> None:  # fmt: skip
    """Check the calibration in CALIBRATION on measurements not used for fitting.

    Prints the nominal (before) and calibrated (after) errors on --data (RMS and max
    position [mm] and orientation [mrad] over the measured components), an ISO
    9283-style pose accuracy table (AP_p, AP_a/b/c per commanded pose; RP_l when
    poses are repeated, i.e. rows with the same actuator values) and the Cramér–Rao
    prediction from the calibration's covariance (without and with the instrument
    noise; withheld, with the reason, when the covariance is not valid or
    ill-conditioned, a parameter's σ exceeds 20 mm / 0.1 rad, or parameters were held
    for weakness). Warns when --data was fitted on, or simulated on another machine (its
    truth.json). A --data file over 100000 rows is refused (with an estimate) unless --yes.

    A calibration with joint terms (joint_terms.yaml: compliance under the recorded
    payload, gain, harmonics, struts' compliance) predicts with its geometry and its
    terms: each command moves the joints by the terms' deflection, as compensate assumes;
    --payload changes the load the compliance sees; a thermal one each pose's temperature_C.

    \b
    Examples:
      pincal simulate hexaslide_6pus --random 20 --seed 9 --out held_out.csv
      pincal validate cal/ --data held_out.csv
      pincal validate cal/ --data held_out.csv --json
      pincal validate cal/ --cv 5 --seed 0      5-fold cross-validation of the fit

    With --cv K the poses the calibration was fitted on are split into K folds (seeded);
    each fold is predicted by a calibration refitted, as calibrate ran it, on the other
    folds. Printed: held-out RMS / max [mm] beside the fit RMS, and beside the same for
    the registration-only model (instrument frame + marker, the uncalibrated robot) for
    a marker calibration, or the nominal model otherwise; and whether the calibration
    beats it by more than the standard error. A marker calibration records the
    cross-validation its gate ran; the same K and seed reuse it (said in the output),
    --refit fits the folds again. With orientation measured (a 6-D marker body) the
    verdict weighs position and orientation, each whitened by its noise σ. A
    calibration from instrument files (ballbar, probe…) is cross-validated on its
    readings, beside the nominal machine with only the instruments fitted.
    """
    from pincal.io import atomic_write_text, read_calibration

    if data is None and cv_folds is None:
        raise click.UsageError("give --data (held-out measurements) or --cv K (or both)")
    if out is not None or folds_out is not None:
        guard_outputs(calibration, data, cv_folds is not None, out, folds_out)
    cal = read_calibration(calibration)
    cv = None
    if cv_folds is not None:
        from pincal.workflow import cross_validate_calibration, fold_table

        cv = cross_validate_calibration(cal, cv_folds, cv_seed, refit)
        if folds_out is not None:
            atomic_write_text(folds_out, fold_table(cv.folds, cv.poses))
        if data is None:
            from pincal.report import cross_validation_text

            only = {"calibration": str(calibration), "cv": cv.to_dict()}
            if out is not None:
                atomic_write_text(out, json.dumps(only, indent=1) + "\n")
            click.echo(json.dumps(only) if as_json else cross_validation_text(cv), nl=as_json)
            return
    assert data is not None
    from pincal.workflow import read_held_out, validate_on_data

    announce(cal)
    held = read_held_out(cal, data, lambda n: check_data_rows(str(data), "--data", n, yes))
    for w in held.warnings:
        click.echo(f"pincal: warning: {w}", err=True)
    if not held.independent:
        click.echo(f"pincal: warning: {data} was used to fit this calibration", err=True)
    terms, line = calibration_terms(cal, read_payload(payload),
                                    per_pose=held.meas.temperature is not None)  # fmt: skip
    found = validate_on_data(cal, held, terms, line, cv_seed)
    doc = {"calibration": calibration_summary(cal), **found.to_dict()}
    if cv is not None:
        doc["cv"] = cv.to_dict()
    if out is not None:
        atomic_write_text(out, json.dumps(doc, indent=1) + "\n")
    if as_json:
        click.echo(json.dumps(doc))
    else:
        echo_data_validation(found, cal, cv)
