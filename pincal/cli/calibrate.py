"""`pincal calibrate`: identify a model's parameters from a measurement file."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import TYPE_CHECKING

import click

from pincal.cli._calibrate_markers import calibrate_markers
from pincal.cli._calibrate_text import result_json
from pincal.cli._instrument_fit import identify_instrument_files, is_instrument_file
from pincal.cli._limits import NOISE_RANGE, check_data_rows, number_pair, yes_option
from pincal.cli._marker_root import root_option, with_root
from pincal.cli._markers import marker_options
from pincal.cli.common import (
    ModelOptions,
    fail_cleanly,
    guard_paths,
    load_model,
    model_input,
    model_options,
    model_record,
    model_source,
)
from pincal.errors import PincalError
from pincal.identification import METHODS

if TYPE_CHECKING:  # imported in the calls: the CLI starts without the model stack
    from pincal.identification import IdentificationResult
    from pincal.measure import Measurements
    from pincal.model import Mechanism, ParameterSet


@click.command()
@click.argument("model")
@click.option(
    "--data",
    required=True,
    multiple=True,
    type=click.Path(dir_okay=False),
    help="Measurement CSV (pincal measurements format); repeat it for several instrument "
    "files fitted together (e.g. socket files of one plate, several tool positions).",
)
@click.option("--params", "preset", default=None, help="Parameter preset (default: first preset).")
@click.option(
    "--model",
    "error_model",
    default="geometric",
    show_default=True,
    help="Error model: 'geometric' or geometric+TERM[+TERM…] with TERM compliance (under "
    "gravity + payload; closed loops by their equilibrium), gain, harmonics: joint-space "
    "terms on every actuated joint, identified beside the geometric parameters; "
    "temperature: thermal expansion of each actuated joint's length (needs a per-pose "
    "temperature_C column, °C, that varies); strut-compliance: the axial yield of "
    "fixed-length struts (a hexaslide's) under the loop-closure forces.",
)
@click.option(
    "--payload",
    default=None,
    metavar="MASS[,X,Y,Z]",
    help="Payload on the tool during the measurements (kg; centre of mass in m in the tool "
    "frame), e.g. 20,0,0,0.1: part of the load a compliance term sees.",
)
@click.option(
    "--method",
    type=click.Choice(list(METHODS)),
    default="gauss-newton",
    show_default=True,
    help="Identification solver.",
)
@click.option(
    "--out",
    required=True,
    type=click.Path(file_okay=False),
    help="Calibration directory to write: calibration.json, calibrated.urdf + "
    "calibrated.yaml, identification.json, report.txt.",
)
@click.option(
    "--json",
    "as_json",
    is_flag=True,
    help="Print identification.json on stdout instead of the report.",
)
@click.option(
    "--noise",
    default=None,
    help="Instrument noise 1σ 'pos_mm,ori_mrad' (overrides the file's '# noise:'); "
    "default: the file's, else estimated from the residuals.",
)
@click.option(
    "--loss",
    type=click.Choice(["auto", "linear", "huber", "soft_l1", "cauchy"]),
    default=None,
    help="Robust loss (needs --method lm); poses it down-weights are reported. Default: "
    "linear; with --link auto (least squares, then huber when the outlier test names poses).",
)
@click.option(
    "--force",
    is_flag=True,
    help="Write the calibration even when the quality gate refuses it (recorded).",
)
@click.option(
    "--max-change",
    default=None,
    metavar="MM,RAD",
    help="Quality gate: largest parameter change [default: 20,0.1].",
)
@click.option(
    "--significance",
    type=float,
    default=None,
    metavar="P",
    help="Quality gate: p-value below which the χ² test (declared noise) and the "
    "misspecification probes (scale, actuator gains, drift, coordinate trends) refuse "
    "[default: 1e-3].",
)
@click.option(
    "--instrument",
    "instrument",
    default=None,
    metavar="NAME",
    help="Instrument profile judging an estimated noise: laser-tracker, motion-capture, "
    "ballbar, touch-probe, cmm (overrides the file's '# instrument:').",
)
@click.option(
    "--bootstrap",
    "bootstrap",
    type=click.IntRange(min=0),
    default=0,
    metavar="N",
    help="Also run N parametric-bootstrap refits (e.g. 100) and report their σ beside the "
    "linear σ (calibration.json quality.uncertainty.bootstrap); never written as the "
    "covariance. Default: none (no refit runs after the fit).",
)
@click.option(
    "--jobs",
    "n_jobs",
    type=click.IntRange(min=-1),
    default=1,
    show_default=True,
    help="Processes of the --bootstrap refits (-1: every CPU); same σ for any value. Each "
    "worker loads pincal and rebuilds the model (seconds): worth it for long refits.",
)
@yes_option
@model_options
@marker_options
@root_option
@fail_cleanly
def calibrate(
    model: str, data: tuple[str, ...], preset: str | None, error_model: str, payload: str | None,
    method: str, out: str, as_json: bool, noise: str | None, loss: str | None, force: bool,
    max_change: str | None, significance: float | None, instrument: str | None, link: str | None,
    instrument_frame: str, marker_spec: str, marker_columns: tuple[str, ...], length_unit: str,
    orientation_columns: str | None, orientation: str | None, prior_spec: str | None,
    root: str | None, bootstrap: int, n_jobs: int, yes: bool, model_opts: ModelOptions,
) -> None:  # fmt: skip
    """Identify MODEL's geometric parameters from measured poses (--data).

    Writes one calibration directory OUT (whole or not at all) that `pincal view
    --calibrated`, `compensate`, `validate` and `report` read as it is. Without a noise
    declaration (file header or --noise) the noise of each block is estimated from the
    residuals and reported. A quality gate refuses to write a calibration whose data or
    fit are implausible (unit mistake, outliers, failed solve, a χ² beyond the declared
    noise at p < 1e-3, a parameter moving > 20 mm / 0.1 rad, a misspecification probe —
    scale, actuator gains, drift — explaining the residual, an estimated noise beyond
    the --instrument profile); --force writes it anyway. A marker table (--link) is
    judged by 5-fold held-out prediction against the registration alone instead (the
    probes are then diagnostics), with a prior and loss the data choose (--prior auto,
    --loss auto).

    \b
    Examples:
      pincal calibrate hexaslide_6pus --data m.csv --out cal/
      pincal calibrate hexaslide_6pus --data m.csv --noise 0.01,0.02 --out cal/
      pincal calibrate wedge3 --data m.csv --params patent --method lm --loss huber --out cal/
      pincal calibrate tiago --link arm_7_link --data mocap.csv --marker-columns x1,y1,z1 \\
          --out cal/        markers in an unknown instrument frame (prior, loss: auto)
    """
    from pincal.cli._gate import apply_gate, bootstrap_lines, gate_limits, honest_uncertainty
    from pincal.cli._joint_terms import carrying, read_payload, terms_texts
    from pincal.identification import check_quality
    from pincal.io import (
        CALIBRATED_SIDECAR,
        CALIBRATED_URDF,
        MANIFEST,
        MODEL_RECORD,
        calibration_lock,
        check_replaceable,
        read_measurement_file,
        write_calibration,
    )
    from pincal.model import split_model, with_joint_terms
    from pincal.report import calibration_text
    from pincal.sensitivity import parameters

    limits = gate_limits(max_change, significance)
    if bootstrap == 1:
        raise click.BadParameter("give 0 (none) or a number of refits ≥ 2, e.g. 100",
                                 param_hint="--bootstrap")  # fmt: skip
    profile = None
    if instrument is not None:
        from pincal.identification import instrument_profile

        try:
            profile = instrument_profile(instrument).name
        except PincalError as e:
            raise click.BadParameter(str(e), param_hint="--instrument") from None
    files = list(data)
    data_file = files[0]
    if len(files) > 1 and not all(is_instrument_file(f) for f in files):
        raise click.BadParameter(
            "several --data files are fitted together only when all are instrument files "
            "('# pincal instrument' / '# pincal sockets'); give one pose measurement file",
            param_hint="--data",
        )
    terms = split_model(error_model)
    load = read_payload(payload)

    if link is None and loss == "auto":
        raise click.BadParameter("auto applies to marker tables (--link); give linear or a "
                                 "robust loss with --method lm", param_hint="--loss")  # fmt: skip
    loss = loss or ("auto" if link is not None else "linear")
    if loss != "linear" and method != "lm" and link is None:
        raise click.BadParameter(
            f"a robust loss needs --method lm, not {method}", param_hint="--loss"
        )
    guard_paths(
        {"MODEL": model_input(model), "--sidecar": model_opts.sidecar}
        | {f"--data {f}": f for f in files},
        out_dirs={"--out": out},
    )
    click.get_current_context().with_resource(calibration_lock(out))  # until the end
    check_replaceable(out)  # a user's directory is refused before the fit, not after
    declared = None
    if noise is not None:
        pos_mm, ori_mrad = number_pair(
            noise, "--noise", positive=True, form="pos_mm,ori_mrad", bounds=NOISE_RANGE
        )
        declared = {"position": pos_mm, "orientation": ori_mrad}
    if link is not None:
        from pincal.cli._markers import marker_settings, setup_from_options

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
                "files: drop --noise", param_hint="--noise")
        if bootstrap:
            raise click.BadParameter(
                "a marker calibration (--link) is not bootstrapped yet; its σ are the linear "
                "ones (prior rows included)", param_hint="--bootstrap")
        if "home" in model_opts.lock.values():
            raise click.BadParameter(
                "with --link, lock joints at a value (JOINT=VALUE [rad or m]), not at home",
                param_hint="--lock",
            )
        lock_spec = ",".join(f"{k}={v!r}" for k, v in model_opts.lock.items()) or None
        setup = setup_from_options(link, instrument_frame, marker_spec, marker_columns,
                                   length_unit, lock_spec, orientation_columns,
                                   orientation)  # fmt: skip
        setup = with_root(setup, root, link)
        settings = marker_settings(preset, method, prior_spec, loss, limits, profile)
        calibrate_markers(model, data_file, setup, settings, out, as_json, force, yes=yes)
        return
    with_root(None, root, link)  # --root without --link: refused
    if prior_spec is not None:
        raise click.BadParameter("--prior applies to marker calibrations (--link)",
                                 param_hint="--prior")  # fmt: skip
    if orientation_columns is not None or orientation is not None:
        raise click.BadParameter("--orientation-columns and --orientation apply to marker "
                                 "tables (--link); a pose file names its orientation columns "
                                 "itself", param_hint="--orientation-columns")  # fmt: skip
    mech = carrying(load_model(model, model_opts), load)
    preset = preset or (next(iter(mech.presets), "full"))
    params = with_joint_terms(mech, parameters(mech, preset), terms)
    for f in files:
        check_data_rows(f, "--data", len(params), yes)
    if is_instrument_file(data_file):
        if declared is not None or loss != "linear":
            raise click.BadParameter(
                "an instrument file carries its own noise; --noise and --loss apply to "
                "pose measurement files",
                param_hint="--data",
            )
        verdict, result, uncertainty = identify_instrument_files(
            mech, params, files, method, force, limits, profile, bootstrap, n_jobs
        )
        noise_model = None
    else:
        mf = read_measurement_file(data_file, mech)  # its data check is the gate's first look
        meas = mf.measurements
        noise_model = meas.noise
        gate = dataclasses.replace(mf.data_check, limits=limits)
        apply_gate(gate, force, before_fit=True)
        result = _identify_poses(mech, params, preset, meas, method, declared, loss)
        verdict = check_quality(
            result, meas, mech=mech, data=gate, instrument=profile or mf.instrument
        )
        result, verdict, uncertainty = honest_uncertainty(result, verdict, mech, meas,
                                                          declared, loss, bootstrap,
                                                          n_jobs)  # fmt: skip
    quality = apply_gate(verdict, force)
    if uncertainty is not None:
        quality["uncertainty"] = uncertainty
    out_dir = Path(out)
    doc = result_json(result, ", ".join(map(str, files)), CALIBRATED_URDF)
    doc["quality"] = quality
    report = calibration_text(result, {"data": ", ".join(map(str, files)), "quality": quality})
    texts = {"report.txt": report}
    record = model_record(model, model_opts)  # the model with --sidecar/--frame/--lock
    if record is not None:
        texts[MODEL_RECORD] = record
    texts |= terms_texts(result, error_model, terms, load)
    source = str(out_dir.resolve() / MODEL_RECORD) if record else model_source(model)
    cal = write_calibration(
        out_dir,
        result,
        model_source=source,
        data_files=files,
        noise=noise_model,
        annotations={"data": ", ".join(map(str, files)), "quality": quality},
        texts=texts,
        nominal=mech if load is not None else None,  # the payload is part of the model
    )
    if terms:
        click.echo(f"pincal: note: the joint terms ({'+'.join(terms)}) are in joint_terms.yaml; "
                   "calibrated.urdf is the geometric part; compensate applies them, validate "
                   "not yet", err=True)  # fmt: skip
    if as_json:
        click.echo(json.dumps(doc))
    else:
        click.echo(report, nl=False)
        for line in bootstrap_lines(uncertainty):
            click.echo(line)
        click.echo(
            f"wrote calibration directory {cal.path}/ ({MANIFEST}, {CALIBRATED_URDF} + "
            f"{CALIBRATED_SIDECAR}, identification.json, report.txt)"
        )


def _identify_poses(
    mech: Mechanism,
    params: ParameterSet,
    preset: str,
    meas: Measurements,
    method: str,
    declared: dict[str, float] | None,
    loss: str,
) -> IdentificationResult:
    """Identification from a pose / position / target measurement file."""
    import numpy as np

    from pincal.cli._progress import iterations
    from pincal.identification import LMOptions, identify
    from pincal.io import check_enough_poses
    from pincal.model import check_term_data
    from pincal.sensitivity import identifiability
    from pincal.workflow import reduction_line

    if "1/K" in params.units:  # a thermal term: its rank depends on the data's temperatures
        check_term_data(params, meas.conditions)
        structural = identifiability(mech, params, meas.q_act, conditions=meas.conditions)
    else:
        structural = identifiability(mech, params, rng=np.random.default_rng(0))
    check_enough_poses(meas, structural.rank)
    if structural.rank < len(params):
        click.echo(reduction_line(preset, structural.rank, len(params)), err=True)
    click.echo(
        f"… identifying {structural.rank} of {len(params)} parameters from {len(meas)} poses",
        err=True,
    )
    with iterations("identifying") as step:
        result = identify(
            mech,
            params,
            meas,
            method=method,
            progress=step,
            noise=declared,
            options=LMOptions(loss=loss) if method == "lm" else None,
        )
    return result
