"""`pincal simulate`: measurement files from a simulated "actual" machine."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

import click

from pincal.cli._buildable import buildable_mask
from pincal.cli._kinds import SOCKET, InstrumentChoice
from pincal.cli._limits import (
    ERROR_SIZE_RANGE,
    MAX_POSES,
    NOISE_RANGE,
    check_count,
    number_pair,
    yes_option,
)
from pincal.cli.common import (
    ModelOptions,
    fail_cleanly,
    guard_paths,
    load_model,
    model_input,
    model_options,
    overwrite_option,
)
from pincal.measure import DEFAULT_NOISE

if TYPE_CHECKING:
    import numpy as np

    from pincal.measure import InstrumentData, Measurements
    from pincal.model import Mechanism


def parse_errors(spec: str) -> int | None:
    """The seed of ``--errors seed:N``, or None for ``none`` (click.BadParameter otherwise)."""
    if spec == "none":
        return None
    kind, _, seed = spec.partition(":")
    if kind != "seed" or not seed.strip().lstrip("-").isdigit():
        raise click.BadParameter(
            f"{spec!r}: use seed:N (random errors) or none", param_hint="--errors"
        )
    return int(seed)


def parse_pair(spec: str, option: str) -> tuple[float, float]:
    """Two finite numbers ≥ 0 (:func:`pincal.cli._limits.number_pair`)."""
    if option == "--error-size":
        return number_pair(spec, option, form="length_mm,angle_mrad", bounds=ERROR_SIZE_RANGE)
    return number_pair(spec, option, form="position_mm,orientation_mrad", bounds=NOISE_RANGE)


@click.command()
@click.argument("model")
@click.option(
    "--poses",
    "poses_file",
    type=click.Path(dir_okay=False),
    default=None,
    help="Poses file: its actuator columns are the commands (as `pincal poses` writes "
    "them); a file with target poses only is solved by the nominal IK. A commands or "
    "measurements file works too.",
)
@click.option(
    "--random",
    "n_random",
    type=click.IntRange(min=1),
    default=None,
    help="Number of random workspace poses instead of --poses.",
)
@click.option("--params", "preset", default=None, help="Parameter preset (default: first preset).")
@click.option(
    "--errors",
    default="seed:0",
    show_default=True,
    help="Geometric errors of the actual machine: seed:N (uniform draw) or none.",
)
@click.option(
    "--error-size",
    default="1,10",
    show_default=True,
    help="Error bounds 'length_mm,angle_mrad' (uniform ±).",
)
@click.option(
    "--noise",
    default=f"{DEFAULT_NOISE.position:g},{DEFAULT_NOISE.orientation:g}",
    show_default=True,
    help="Measurement noise 1σ 'position_mm,orientation_mrad' (the default of every command).",
)
@click.option("--seed", default=1, type=click.IntRange(min=0), show_default=True,
              help="Seed of poses and noise.")  # fmt: skip
@click.option(
    "--length-unit",
    type=click.Choice(["m", "mm"]),
    default="m",
    show_default=True,
    help="Length unit of the written file (m round-trips exactly).",
)
@click.option(
    "--out",
    required=True,
    type=click.Path(dir_okay=False),
    help="Measurement CSV to write; the true errors go to <out>.truth.json.",
)
@click.option(
    "--instrument",
    type=InstrumentChoice(),
    default=None,
    help="Write one scalar reading per pose (ballbar, sphere probe, planes, gauge, or a "
    "registered kind) instead "
    "of poses, or (socket) the poses of a ball seated in two sockets 50 mm apart (half "
    "of --random each, the known distance declared); its noise is the position noise.",
)
@click.option(
    "--temperature",
    default=None,
    metavar="LOW,HIGH",
    help="Machine temperature range [°C], e.g. 18,28: each pose gets a uniform draw, "
    "written as the temperature_C column, and every actuated joint's length expands by "
    "--thermal (pose files only).",
)
@click.option(
    "--thermal",
    default=12e-6,
    show_default=True,
    type=click.FloatRange(-1e-3, 1e-3),
    help="True thermal expansion coefficient [1/K] with --temperature (steel: 12e-6).",
)
@click.option("--json", "as_json", is_flag=True, help="Print a JSON summary on stdout.")
@yes_option
@overwrite_option
@model_options
@fail_cleanly
def simulate(
    model: str,
    poses_file: str | None,
    n_random: int | None,
    preset: str | None,
    errors: str,
    error_size: str,
    noise: str,
    seed: int,
    length_unit: str,
    out: str,
    instrument: str | None,
    temperature: str | None,
    thermal: float,
    as_json: bool,
    yes: bool,
    overwrite: bool,
    model_opts: ModelOptions,
) -> None:
    """Simulate a measurement campaign of MODEL with random geometric errors.

    The "actual" machine is MODEL with random errors on the preset's parameters; it is
    measured at the commands of the poses file (its actuator columns, or the nominal
    model's IK of its target poses when it has none). The
    measurement file states its units and noise in its header; `pincal calibrate
    --data` and `pincal validate --data` read it.

    \b
    Examples:
      pincal simulate hexaslide_6pus --poses poses.csv --out m.csv
      pincal simulate wedge3 --random 20 --seed 5 --out held_out.csv
      pincal simulate pkm5 --random 30 --noise 0.005,0.02 --length-unit mm --out m.csv
    """
    import numpy as np

    from pincal import __version__
    from pincal.io import (
        atomic_write_text,
        read_pose_rows,
        write_measurements,
    )
    from pincal.measure import (
        NoiseModel,
        simulate_measurements,
    )
    from pincal.model import sample_actuators
    from pincal.sensitivity import parameters

    if (poses_file is None) == (n_random is None):
        raise click.UsageError("give exactly one of --poses FILE or --random N")
    if instrument == SOCKET and n_random is None:
        raise click.UsageError("--instrument socket seats the ball itself: give --random N")
    check_count(n_random, "--random", MAX_POSES, yes)
    err_seed = parse_errors(errors)
    size_mm, size_mrad = parse_pair(error_size, "--error-size")
    pos_mm, ori_mrad = parse_pair(noise, "--noise")
    span = None
    if temperature is not None:
        if instrument is not None:
            raise click.UsageError("--temperature simulates pose files: drop --instrument")
        span = number_pair(temperature, "--temperature", form="low_C,high_C",
                           bounds=(0.0, 200.0))  # fmt: skip
    truth_path = Path(out).with_suffix(".truth.json")
    guard_paths(
        {"MODEL": model_input(model), "--poses": poses_file},
        {"--out": out},
        implied={"--out's truth file": truth_path},
        overwrite=overwrite,
    )
    nominal = load_model(model, model_opts)
    preset = preset or (next(iter(nominal.presets), "full"))
    params = parameters(nominal, preset)
    values = np.zeros(len(params))
    rng = np.random.default_rng(seed)
    if poses_file is not None:
        q_act = read_pose_rows(poses_file, nominal)
    else:
        assert n_random is not None  # exactly one of --poses / --random, checked above
        click.echo(f"… sampling {n_random} random poses", err=True)
        q_act = sample_actuators(nominal, n_random, rng)
    if err_seed is not None:
        er = np.random.default_rng(err_seed)
        bound = np.array([size_mm * 1e-3 if u == "m" else size_mrad * 1e-3 for u in params.units])
        values = er.uniform(-bound, bound) * buildable_mask(nominal, params, q_act, say=True)
    actual = params.apply(nominal, values)
    skipped: list[int] = []
    if instrument != SOCKET:
        q_act, skipped = _reachable(actual, q_act)
    click.echo(f"… measuring {len(q_act)} poses of the actual machine", err=True)
    extra = {}
    meas: Measurements | InstrumentData
    components: list[str]
    if instrument == SOCKET:
        from pincal.cli._sockets import simulate_socket_file

        assert n_random is not None  # --instrument socket needs --random, checked above
        path, n_meas, truth_sockets = simulate_socket_file(
            nominal, actual, n_random, pos_mm * 1e-3, rng, out, length_unit
        )
        meas, components = range(n_meas), ["socket"]  # type: ignore[assignment]
        extra = {"instrument": truth_sockets}
    elif instrument is not None:
        from pincal.identification import default_instrument
        from pincal.io import write_instrument_data
        from pincal.measure import simulate_instrument

        inst, theta, ids = default_instrument(nominal, instrument, q_act, std=pos_mm * 1e-3)
        readings = simulate_instrument(actual, inst, theta, q_act, rng, ids=ids)
        path = write_instrument_data(out, readings, length_unit=length_unit)
        meas, components = readings, [readings.kind]
        extra = {"instrument": dict(zip(inst.parameter_names, map(float, theta), strict=True))}
    elif span is not None:
        import dataclasses

        from pincal.cli._joint_terms import thermal_machine

        q_true, shift, T, alphas = thermal_machine(nominal, q_act, span, thermal, rng)
        poses = simulate_measurements(actual, q_true, NoiseModel(pos_mm, ori_mrad), rng)
        poses = dataclasses.replace(
            poses, q_act=np.array(q_act, dtype=float), positions=poses.positions + shift,
            temperature=T,
        )  # fmt: skip
        path = write_measurements(out, poses, length_unit=length_unit)
        meas, components = poses, list(poses.components)
        extra = {"thermal_1_per_K": alphas}
    else:
        poses = simulate_measurements(actual, q_act, NoiseModel(pos_mm, ori_mrad), rng)
        path = write_measurements(out, poses, length_unit=length_unit)
        meas, components = poses, list(poses.components)
    truth = {
        "written_by": f"pincal {__version__}",
        "model": nominal.name,
        "preset": preset,
        "errors": errors,
        "error_size_mm_mrad": [size_mm, size_mrad],
        "parameters": [
            {"name": n, "unit": u, "value": float(v)}
            for n, u, v in zip(params.names, params.units, values, strict=True)
        ],
        **extra,
        "skipped_rows": skipped,
    }
    atomic_write_text(truth_path, json.dumps(truth, indent=1) + "\n")
    if as_json:
        click.echo(
            json.dumps(
                {
                    "measurements": str(path),
                    "truth": str(truth_path),
                    "model": nominal.name,
                    "preset": preset,
                    "poses": len(meas),
                    "skipped_rows": skipped,
                    "components": components,
                }
            )
        )
    else:
        click.echo(f"wrote {path} ({len(meas)} poses) and {truth_path}")


def _reachable(actual: Mechanism, q_act: np.ndarray) -> tuple[np.ndarray, list[int]]:
    """The rows (m, n_act) the actual machine reaches and the others' 1-based numbers.

    Says on stderr how many were skipped, which and why.

    A pose the erroneous machine cannot close on its home assembly branch (its loops
    open near the workspace's edge) is left out of the campaign, as a measurement
    campaign skips a pose the machine refuses.

    Raises:
        ConvergenceError: the actual machine reaches none of the rows.
    """
    import numpy as np

    from pincal.errors import ConvergenceError

    ok = actual.closable_batch(q_act)
    skipped = [int(i) + 1 for i in np.flatnonzero(~ok)]
    if not ok.any():
        raise ConvergenceError(
            f"the actual machine (the model with the simulated errors) reaches none of the "
            f"{len(q_act)} poses: its loops do not close on home's assembly branch there; "
            "choose poses away from the workspace's edges or smaller --error-size"
        )
    if skipped:
        shown = ", ".join(map(str, skipped[:20])) + (", …" if len(skipped) > 20 else "")
        click.echo(
            f"skipped {len(skipped)} of {len(q_act)} poses the actual machine cannot reach "
            f"(its loops do not close on home's assembly branch with the simulated errors, "
            f"at the workspace's edge): rows {shown}; the file lists the {int(ok.sum())} "
            "reached",
            err=True,
        )
    return np.asarray(q_act)[ok], skipped
