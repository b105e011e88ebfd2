"""`pincal acceptance`: ISO 9283 pose accuracy and repeatability on the test cube."""

from __future__ import annotations

import json

import click

from pincal.cli._limits import MAX_POSES, check_count, check_number, yes_option
from pincal.cli._paths import guard_paths
from pincal.cli.common import (
    ModelOptions,
    announce,
    fail_cleanly,
    load_model,
    model_input,
    model_options,
)


@click.command()
@click.argument("model")
@click.option("--calibrated", "cal", default=None,
              help="Calibration directory (calibrated.urdf + .yaml, or identification.json) "
              "or an identification.json: the controller model after calibration.")
@click.option("--data", "data_file", type=click.Path(dir_okay=False), default=None,
              help="Measured repeated poses (pincal measurements CSV; its components are "
              "judged, at least one position axis; rows with equal actuator values are one "
              "commanded pose) instead of a simulation.")
@click.option("--params", "preset", default=None, help="Preset of the simulated errors.")
@click.option("--errors", default="seed:0", show_default=True, help="seed:N or none.")
@click.option("--error-size", default="1,10", show_default=True, help="'length_mm,angle_mrad'.")
@click.option("--cycles", default=30, show_default=True, type=click.IntRange(min=2))
@click.option("--repeatability", default=2.0, show_default=True,
              help="Actuator repeatability 1σ [µm].")
@click.option("--seed", default=1, type=click.IntRange(min=0), show_default=True,
              help="Seed of the cube search and cycles.")  # fmt: skip
@click.option("--out", "json_out", type=click.Path(dir_okay=False), default=None,
              help="Also write the AP/RP report as JSON to this file.")
@click.option("--json", "as_json", is_flag=True, help="Print the report as JSON on stdout.")
@yes_option
@model_options
@fail_cleanly
def acceptance(
    model: str, cal: str | None, data_file: str | None, preset: str | None, errors: str,
    error_size: str, cycles: int, repeatability: float, seed: int, json_out: str | None,
    as_json: bool, yes: bool, model_opts: ModelOptions,
) -> None:  # fmt: skip
    """ISO 9283 acceptance of MODEL: AP and RP at P1–P5 of the test cube.

    The test uses the components MODEL measures: a cube in x, y, z, a square in the
    plane of two measured position axes (x, y for a planar machine; orientation only
    where measured, e.g. rz). It is the largest one whose lattice the machine reaches
    (inverse then forward kinematics) inside the sidecar's declared workspace.pose, or,
    without one, inside the sampled reachable workspace; the output says which. When
    none fits, the command stops and says what to change. AP_a/b/c follow ISO 9283:
    differences of the angles a, b, c about the base x, y, z axes [mrad].

    Simulates the actual machine (MODEL with the errors of `pincal simulate`, same
    defaults) commanded by the nominal model (before) and by the calibrated one
    (after, with --calibrated), or evaluates measured cycles (--data). A calibration of
    another robot is refused; one whose data's simulate truth differs is warned about.

    \b
    Examples:
      pincal acceptance stewart_6ups                      before calibration only
      pincal acceptance stewart_6ups --calibrated cal/    before and after
      pincal acceptance stewart_6ups --data cycles.csv --out iso.json
    """
    from pincal.cli._progress import counted
    from pincal.cli._simulate_options import parse_errors, parse_pair
    from pincal.io import atomic_write_text
    from pincal.validation import iso_test_cube
    from pincal.workflow import (
        acceptance_machine,
        calibrated_controller,
        cube_doc,
        cycle_characteristics,
        measured_characteristics,
        other_machine,
    )

    guard_paths({"MODEL": model_input(model), "--calibrated": cal, "--data": data_file},
                {"--out": json_out})  # fmt: skip
    check_count(cycles, "--cycles", MAX_POSES // 5, yes, least=2, what="cycles of 5 poses")
    check_number(repeatability, "--repeatability")
    parse_pair(error_size, "--error-size")
    say = (lambda _line: None) if as_json else click.echo
    nominal = load_model(model, model_opts)
    calibrated = calibrated_controller(cal, nominal, announce) if cal else None
    report: dict = {"model": nominal.name}
    if data_file is not None:
        pc = measured_characteristics(data_file, nominal, calibrated or nominal)
        for line in pc.lines(f"measured ({data_file}), commands from the "
                             f"{'calibrated' if calibrated else 'nominal'} model"):  # fmt: skip
            say(line)
        report["measured"] = pc.to_dict()
    else:
        cube = iso_test_cube(nominal, rng=seed)
        say(cube.describe())
        report["cube"] = cube_doc(cube)
        err_seed = parse_errors(errors)
        size_mm, size_mrad = parse_pair(error_size, "--error-size")
        sim = acceptance_machine(nominal, preset, err_seed, size_mm, size_mrad)
        if cal:
            for line in other_machine(cal, sim.params, sim.values, sim.settings(errors)):
                click.echo(f"pincal: warning: {line}", err=True)
        runs = [("before", nominal)] + ([("after", calibrated)] if calibrated else [])
        for label, controller in runs:
            with counted(f"{label}: cycles", unit="cycle") as step:
                pc = cycle_characteristics(sim.actual, controller, cube, cycles,
                                           repeatability * 1e-6, seed, step)  # fmt: skip
            for line in pc.lines(f"{label} calibration (simulated, {cycles} cycles)"):
                say(line)
            report[label] = pc.to_dict()
    if json_out:
        atomic_write_text(json_out, json.dumps(report, indent=1) + "\n")
        say(f"wrote {json_out}")
    if as_json:
        click.echo(json.dumps(report))
