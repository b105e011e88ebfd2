"""`pincal simulate`: measurement files from a simulated "actual" machine."""

from __future__ import annotations

import json
from pathlib import Path

import click

from pincal.cli._kinds import SOCKET
from pincal.cli._limits import MAX_POSES, check_count, number_pair, yes_option
from pincal.cli._paths import guard_paths, overwrite_option
from pincal.cli._simulate_options import parse_errors, parse_pair, simulate_options
from pincal.cli.common import ModelOptions, fail_cleanly, load_model, model_input, model_options


@click.command()
@click.argument("model")
@simulate_options
@yes_option
@overwrite_option
@model_options
@fail_cleanly
def simulate(
    model: str, poses_file: str | None, n_random: int | None, preset: str | None, errors: str,
    error_size: str, noise: str, seed: int, length_unit: str, out: str, instrument: str | None,
    temperature: str | None, thermal: float, as_json: bool, yes: bool, overwrite: bool,
    model_opts: ModelOptions,
) -> None:  # fmt: skip
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
    from pincal import __version__
    from pincal.io import (
        atomic_write_text,
        write_instrument_data,
        write_measurements,
        write_socket_data,
    )
    from pincal.measure import InstrumentData, SocketData
    from pincal.workflow import ThermalDraw, simulate_campaign

    if (poses_file is None) == (n_random is None):
        raise click.UsageError("give exactly one of --poses FILE or --random N")
    if instrument == SOCKET and n_random is None:
        raise click.UsageError("--instrument socket seats the ball itself: give --random N")
    check_count(n_random, "--random", MAX_POSES, yes)
    err_seed = parse_errors(errors)
    size = parse_pair(error_size, "--error-size")
    pos_ori = parse_pair(noise, "--noise")
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
    run = simulate_campaign(
        nominal, preset, poses_file, n_random, error_seed=err_seed, error_size=size,
        noise=pos_ori, seed=seed, instrument=None if instrument == SOCKET else instrument,
        sockets=instrument == SOCKET, say=lambda line: click.echo(line, err=True),
        thermal=None if span is None else ThermalDraw(span, thermal),
    )  # fmt: skip
    if isinstance(run.data, SocketData):
        path = write_socket_data(out, run.data, length_unit=length_unit)
    elif isinstance(run.data, InstrumentData):
        path = write_instrument_data(out, run.data, length_unit=length_unit)
    else:
        path = write_measurements(out, run.data, length_unit=length_unit)
    truth = run.truth(f"pincal {__version__}", errors)
    atomic_write_text(truth_path, json.dumps(truth, indent=1) + "\n")
    if as_json:
        click.echo(
            json.dumps(
                {
                    "measurements": str(path),
                    "truth": str(truth_path),
                    "model": nominal.name,
                    "preset": preset,
                    "poses": len(run.data),
                    "skipped_rows": run.skipped,
                    "components": list(run.components),
                }
            )
        )
    else:
        click.echo(f"wrote {path} ({len(run.data)} poses) and {truth_path}")
