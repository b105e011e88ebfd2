"""`pincal validate`: errors of a calibration on held-out measurements."""

from __future__ import annotations

import json
from pathlib import Path

import click

from pincal.cli._joint_terms import payload_option, read_payload
from pincal.cli._limits import check_data_rows, yes_option
from pincal.cli.common import announce, calibration_summary, fail_cleanly


@click.command()
@click.argument("calibration", type=click.Path(path_type=Path))
@click.option(
    "--data",
    default=None,
    type=click.Path(dir_okay=False, path_type=Path),
    help="Held-out measurement file (not used for fitting); required without --cv.",
)
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
@click.option(
    "--out",
    type=click.Path(dir_okay=False, path_type=Path),
    default=None,
    help="Also write the full validation JSON to this file (for `pincal report --validation`).",
)
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
    ill-conditioned, a parameter's 2σ exceeds 20 mm / 0.1 rad, or parameters were held
    for weakness). Warns when --data is a file the calibration was fitted on. A --data
    file of more than 100000 rows is refused (with an estimate) unless --yes.

    A calibration with joint terms (joint_terms.yaml: compliance under the recorded
    payload, gain, harmonics, struts' compliance) predicts with its geometry and its
    terms: each command moves the joints by the terms' deflection, as compensate
    assumes; --payload changes the load the compliance sees.

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
    verdict weighs position and orientation, each whitened by its noise σ.
    """
    from pincal.cli.common import guard_paths
    from pincal.io import (
        IDENTIFICATION_FILE,
        MANIFEST,
        atomic_write_text,
        read_calibration,
        read_measurement_file,
        sha256_file,
    )

    if data is None and cv_folds is None:
        raise click.UsageError("give --data (held-out measurements) or --cv K (or both)")
    if out is not None or folds_out is not None:
        from pincal.cli._implicit_inputs import calibration_inputs

        inputs: dict = {} if data is None else {"--data": data}
        inputs |= {f"CALIBRATION's {n}": calibration / n
                   for n in (IDENTIFICATION_FILE, MANIFEST)}  # fmt: skip
        # its files, its nominal model's and (--cv) the data file the folds are read from
        inputs |= calibration_inputs(calibration, data_files=cv_folds is not None)
        guard_paths(inputs, {"--out": out, "--folds-out": folds_out})
    cv = cv_doc = None
    if cv_folds is not None:
        from pincal.cli._cv import run_cv
        from pincal.report import cross_validation_text

        cv = run_cv(read_calibration(calibration), cv_folds, cv_seed, folds_out, refit)
        cv_doc = cv.to_dict()
        if data is None:
            only = {"calibration": str(calibration), "cv": cv_doc}
            if out is not None:
                atomic_write_text(out, json.dumps(only, indent=1) + "\n")
            click.echo(json.dumps(only) if as_json else cross_validation_text(cv), nl=as_json)
            return
    assert data is not None
    from pincal.sensitivity import parameters
    from pincal.validation import marker_errors, validate_held_out

    cal = read_calibration(calibration)
    announce(cal)
    nominal = cal.nominal()
    params = parameters(nominal, cal.preset)
    check_data_rows(str(data), "--data", len(params), yes)
    more: tuple = ()  # further markers' measurement sets
    if cal.manifest.get("markers"):  # a marker table, read as calibrate read it
        from pincal.io import read_marker_sets
        from pincal.measure import MarkerSetup

        setup = MarkerSetup.from_dict(cal.manifest["markers"])
        meas, *rest = read_marker_sets(data, nominal, setup)
        more = tuple(zip(setup.more_columns, rest, strict=True))
    else:
        mf = read_measurement_file(data, nominal)
        for w in mf.warnings:
            click.echo(f"pincal: warning: {w}", err=True)
        meas = mf.measurements
    digest = sha256_file(data)
    fitted = {d.get("sha256") for d in cal.manifest.get("data_files", []) or []}
    independent = digest not in fitted
    if not independent:
        click.echo(f"pincal: warning: {data} was used to fit this calibration", err=True)
    result = cal.result
    from pincal.cli._joint_terms import calibration_terms
    from pincal.identification import covariance_kind

    terms, terms_line = calibration_terms(cal, read_payload(payload),
                                          per_pose=meas.temperature is not None)  # fmt: skip
    if terms is not None and "1/K" in terms.params.units and meas.temperature is None:
        from pincal.errors import ConditionError

        raise ConditionError(
            f"{data} has no 'temperature_C' column, but calibration {str(cal.path)!r} has a "
            f"thermal term (calibrate --model geometric+temperature): it predicts each pose at "
            f"its own temperature, and at the reference 20 °C it would predict a machine at "
            f"20 °C, not the measured one; add the per-pose machine temperature [°C] as a "
            f"temperature_C column (as the calibration data had)"
        )
    validation = validate_held_out(
        nominal,
        cal.calibrated(),
        meas,
        params,
        tuple(result.identified_names),
        result.covariance,
        meas.noise or cal.noise,
        tuple((cal.manifest.get("markers") or {}).get("held_weak") or ()),
        None if terms is None else meas.q_act + terms.deflection(meas.q_act, meas.conditions),
        covariance_kind(result.annotations,
                        None if result.weighting is None else result.weighting.source),
        None if terms is None else terms.shift(meas.q_act, meas.conditions),
    )
    doc = {
        "calibration": calibration_summary(cal),
        "data": str(data),
        "data_sha256": digest,
        "independent": independent,
        "joint_terms": terms_line or None,
        **validation.to_dict(),
    }
    markers = marker_errors(nominal, cal.calibrated(), more) if more else []
    if markers:
        doc["more_markers"] = [m.to_dict() for m in markers]
    transfer = None
    if (cal.manifest.get("markers") or {}).get("instrument_frame") == "unknown":
        from pincal.workflow import transfer_markers

        transfer = transfer_markers(cal, data, 5, cv_seed)
        doc["transfer"] = transfer.to_dict()
    if cv_doc is not None:
        doc["cv"] = cv_doc
    if out is not None:
        atomic_write_text(out, json.dumps(doc, indent=1) + "\n")
    if as_json:
        click.echo(json.dumps(doc))
    else:
        from pincal.report import marker_errors_text, validation_text

        if terms_line:
            click.echo(f"calibrated model: geometry and {terms_line} (joint = command + "
                       f"deflection; the nominal: commands)")  # fmt: skip
        click.echo(validation_text(validation, cal, str(data), independent), nl=False)
        click.echo(marker_errors_text(markers), nl=False)
        if transfer is not None:
            from pincal.report import transfer_text

            click.echo("(above: the instrument frame and marker as calibrated — the same "
                       "capture set-up only)")  # fmt: skip
            click.echo(transfer_text(transfer, str(data)), nl=False)
        if cv is not None:
            from pincal.report import cross_validation_text

            click.echo(cross_validation_text(cv), nl=False)
