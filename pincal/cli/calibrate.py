"""`pincal calibrate`: identify a model's parameters from a measurement file."""

from __future__ import annotations

import click

from pincal.cli._calibrate_markers import calibrate_markers, refuse_pose_options
from pincal.cli._calibrate_options import calibrate_options
from pincal.cli._calibrate_poses import calibrate_poses, is_instrument_file, refuse_marker_options
from pincal.cli._limits import NOISE_RANGE, number_pair
from pincal.cli._marker_root import with_root
from pincal.cli._paths import guard_paths
from pincal.cli.common import ModelOptions, fail_cleanly, model_input
from pincal.errors import PincalError


@click.command()
@click.argument("model")
@calibrate_options
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
      pincal calibrate wedge3 --data m.csv --params patent --loss huber --out cal/
      pincal calibrate tiago --link arm_7_link --data mocap.csv --marker-columns x1,y1,z1 \\
          --out cal/        markers in an unknown instrument frame (prior, loss: auto)
    """
    from pincal.cli._gate import gate_limits
    from pincal.cli._joint_terms import read_payload
    from pincal.io import calibration_lock, check_replaceable
    from pincal.model import split_model

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
    if len(files) > 1 and not all(is_instrument_file(f) for f in files):
        raise click.BadParameter(
            "several --data files are fitted together only when all are instrument files "
            "('# pincal instrument' / '# pincal sockets'); give one pose measurement file",
            param_hint="--data",
        )
    terms = split_model(error_model)
    load = read_payload(payload)
    if link is None and loss == "auto":
        raise click.BadParameter("auto applies to marker tables (--link); give linear or "
                                 "a robust loss (huber, soft_l1, cauchy)",
                                 param_hint="--loss")  # fmt: skip
    loss = loss or ("auto" if link is not None else "linear")
    if loss != "linear" and method not in ("gauss-newton", "lm") and link is None:
        raise click.BadParameter(f"a robust loss needs --method gauss-newton or lm, not "
                                 f"{method}", param_hint="--loss")  # fmt: skip
    guard_paths({"MODEL": model_input(model), "--sidecar": model_opts.sidecar}
                | {f"--data {f}": f for f in files}, out_dirs={"--out": out})  # fmt: skip
    click.get_current_context().with_resource(calibration_lock(out))  # until the end
    check_replaceable(out)  # a user's directory is refused before the fit, not after
    declared = None
    if noise is not None:
        pos_mm, ori_mrad = number_pair(noise, "--noise", positive=True, form="pos_mm,ori_mrad",
                                       bounds=NOISE_RANGE)  # fmt: skip
        declared = {"position": pos_mm, "orientation": ori_mrad}
    if link is not None:
        from pincal.cli._markers import marker_settings, setup_from_options

        refuse_pose_options(terms, load, model_opts, noise, bootstrap)
        lock_spec = ",".join(f"{k}={v!r}" for k, v in model_opts.lock.items()) or None
        setup = setup_from_options(link, instrument_frame, marker_spec, marker_columns,
                                   length_unit, lock_spec, orientation_columns,
                                   orientation)  # fmt: skip
        setup = with_root(setup, root, link)
        settings = marker_settings(preset, method, prior_spec, loss, limits, profile)
        calibrate_markers(model, files[0], setup, settings, out, as_json, force, yes=yes)
        return
    with_root(None, root, link)  # --root without --link: refused
    refuse_marker_options(prior_spec, orientation_columns, orientation)
    calibrate_poses(model, model_opts, files, preset, error_model, load, method, declared, loss,
                    limits, profile, bootstrap, n_jobs, force, yes, out, as_json)  # fmt: skip
