"""`pincal acceptance`: ISO 9283 pose accuracy and repeatability on the test cube."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

import click

from pincal.cli._limits import MAX_POSES, check_count, check_number, yes_option
from pincal.cli.common import (
    ModelOptions,
    fail_cleanly,
    guard_paths,
    load_model,
    model_input,
    model_options,
)

if TYPE_CHECKING:
    import numpy as np
    import pinocchio as pin

    from pincal.measure import Measurements
    from pincal.model import Mechanism, ParameterSet


def load_calibrated(spec: str, nominal: Mechanism) -> Mechanism:
    """The calibrated machine from a calibration directory or an identification.json.

    A calibration directory is read (and checked) by :func:`pincal.io.read_calibration`;
    a directory without a manifest, or a file, through its identification.json
    (:func:`pincal.io.read_identification`): the record's values applied to ``nominal``.

    Raises:
        CalibrationDirectoryError / ParameterError: nothing usable at ``spec``, or a
            record of another model.
    """
    from pincal.cli.common import announce
    from pincal.errors import ParameterError
    from pincal.io import IDENTIFICATION_FILE, MANIFEST, read_calibration, read_identification

    path = Path(spec)
    if (path / MANIFEST).is_file():  # a calibration directory: read (and checked) as one
        cal = read_calibration(path)
        announce(cal)
        return cal.calibrated()
    if path.is_dir():
        path = path / IDENTIFICATION_FILE
    record = read_identification(path)
    try:
        return record.applied_to(nominal)
    except ParameterError as exc:
        raise ParameterError(f"{str(path)!r}: {exc}") from None


def _other_machine(cal: str, params: ParameterSet, values: np.ndarray) -> list[str]:
    """Warnings when the simulated machine is not the one the calibration was fitted on.

    A calibration of simulated data records its data file; ``pincal simulate`` wrote the
    truth beside it (``<data>.truth.json``). When the errors simulated here differ from
    that truth, the "after" figures test the calibration on another machine.
    """
    import json as _json

    import numpy as np

    from pincal.errors import CalibrationDirectoryError
    from pincal.io import MANIFEST, read_calibration

    if not (Path(cal) / MANIFEST).is_file():
        return []
    directory = read_calibration(cal)
    out = []
    for k in range(len(directory.manifest.get("data_files") or [])):
        try:  # found by its hash, wherever calibrate ran
            truth_path = directory.data_file(k).with_suffix(".truth.json")
        except CalibrationDirectoryError:
            continue
        if not truth_path.is_file():
            continue
        try:
            truth = _json.loads(truth_path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            continue
        true = {p["name"]: p["value"] for p in truth.get("parameters", [])}
        here = dict(zip(params.names, np.asarray(values, dtype=float), strict=True))
        same = set(true) == set(here) and all(abs(true[n] - here[n]) <= 1e-12 for n in true)
        if not same:
            size = truth.get("error_size_mm_mrad")
            hint = f"--errors {truth.get('errors')} --params {truth.get('preset')}"
            hint += f" --error-size {size[0]:g},{size[1]:g}" if size else ""
            out.append(f"the machine simulated here is not the one the calibration was fitted "
                       f"on ({truth_path} differs): the 'after' figures test the calibration on "
                       f"another machine; to test it on its own, pass {hint}")  # fmt: skip
    return out


def _grouped(
    meas: Measurements, controller: Mechanism
) -> tuple[list[pin.SE3], np.ndarray, np.ndarray | None]:
    """Commands (forward kinematics of the distinct actuator rows) and the poses per row."""
    import numpy as np

    from pincal.errors import MeasurementError

    keys, first, inverse = np.unique(meas.q_act, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)
    counts = np.bincount(inverse.reshape(-1))
    if len(set(counts.tolist())) != 1 or counts[0] < 2:
        raise MeasurementError(
            f"every commanded pose must be measured the same number (≥ 2) of times; got "
            f"counts {counts[order].tolist()}"
        )
    if meas.rotations is None and any(c.startswith("r") for c in meas.components):
        raise MeasurementError(
            f"the file declares components {' '.join(meas.components)} but holds no "
            "orientation; measure the orientation or declare position components only"
        )
    poses, pos, rot = [], [], []
    for g in order:
        rows = np.flatnonzero(inverse.reshape(-1) == g)
        poses.append(controller.forward(keys[g]))
        pos.append(meas.positions[rows])
        if meas.rotations is not None:
            rot.append(meas.rotations[rows])
    return poses, np.array(pos), (np.array(rot) if rot else None)


@click.command()
@click.argument("model")
@click.option(
    "--calibrated",
    "cal",
    default=None,
    help="Calibration directory (calibrated.urdf + .yaml, or identification.json) or an "
    "identification.json: the controller model after calibration.",
)
@click.option(
    "--data",
    "data_file",
    type=click.Path(dir_okay=False),
    default=None,
    help="Measured repeated poses (pincal measurements CSV; its components are judged, "
    "at least one position axis; rows with equal actuator values are one commanded pose) "
    "instead of a simulation.",
)
@click.option("--params", "preset", default=None, help="Preset of the simulated errors.")
@click.option("--errors", default="seed:0", show_default=True, help="seed:N or none.")
@click.option("--error-size", default="1,10", show_default=True, help="'length_mm,angle_mrad'.")
@click.option("--cycles", default=30, show_default=True, type=click.IntRange(min=2))
@click.option(
    "--repeatability", default=2.0, show_default=True, help="Actuator repeatability 1σ [µm]."
)
@click.option("--seed", default=1, type=click.IntRange(min=0), show_default=True,
              help="Seed of the cube search and cycles.")  # fmt: skip
@click.option(
    "--out",
    "json_out",
    type=click.Path(dir_okay=False),
    default=None,
    help="Also write the AP/RP report as JSON to this file.",
)
@click.option("--json", "as_json", is_flag=True, help="Print the report as JSON on stdout.")
@yes_option
@model_options
@fail_cleanly
def acceptance(
    model: str,
    cal: str | None,
    data_file: str | None,
    preset: str | None,
    errors: str,
    error_size: str,
    cycles: int,
    repeatability: float,
    seed: int,
    json_out: str | None,
    as_json: bool,
    yes: bool,
    model_opts: ModelOptions,
) -> None:
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
    (after, with --calibrated), or evaluates measured cycles (--data).

    \b
    Examples:
      pincal acceptance stewart_6ups                      before calibration only
      pincal acceptance stewart_6ups --calibrated cal/    before and after
      pincal acceptance stewart_6ups --data cycles.csv --out iso.json
    """
    import numpy as np

    from pincal.cli._progress import counted
    from pincal.cli._simulate_options import parse_errors, parse_pair
    from pincal.io import atomic_write_text, read_measurements
    from pincal.sensitivity import parameters
    from pincal.validation import iso_test_cube, pose_characteristics, simulate_cycles

    guard_paths(
        {"MODEL": model_input(model), "--calibrated": cal, "--data": data_file},
        {"--out": json_out},
    )
    check_count(cycles, "--cycles", MAX_POSES // 5, yes, least=2, what="cycles of 5 poses")
    check_number(repeatability, "--repeatability")
    parse_pair(error_size, "--error-size")
    say = (lambda _line: None) if as_json else click.echo
    nominal = load_model(model, model_opts)
    calibrated = load_calibrated(cal, nominal) if cal else None
    report: dict = {"model": nominal.name}
    if data_file is not None:
        controller = calibrated or nominal
        meas = read_measurements(data_file, nominal)
        poses, pos, rot = _grouped(meas, controller)
        pc = pose_characteristics(poses, pos, rot, tuple(meas.components))
        for line in pc.lines(f"measured ({data_file}), commands from the "
                             f"{'calibrated' if calibrated else 'nominal'} model"):  # fmt: skip
            say(line)
        report["measured"] = pc.to_dict()
    else:
        cube = iso_test_cube(nominal, rng=seed)
        say(cube.describe())
        report["cube"] = {
            "shape": cube.shape,
            "axes": list(cube.axes),
            "components": list(cube.components),
            "workspace": cube.workspace,
            "bounds": np.asarray(cube.bounds).tolist(),
            "centre": cube.centre.tolist(),
            "edge": cube.edge,
            "points": cube.points.tolist(),
        }
        err_seed = parse_errors(errors)
        size_mm, size_mrad = parse_pair(error_size, "--error-size")
        params = parameters(nominal, preset or next(iter(nominal.presets), "full"))
        values = np.zeros(len(params))
        if err_seed is not None:
            er = np.random.default_rng(err_seed)
            bound = np.array(
                [size_mm * 1e-3 if u == "m" else size_mrad * 1e-3 for u in params.units]
            )
            values = er.uniform(-bound, bound)
        actual = params.apply(nominal, values)
        if cal:
            for line in _other_machine(cal, params, values):
                click.echo(f"pincal: warning: {line}", err=True)
        runs = [("before", nominal)] + ([("after", calibrated)] if calibrated else [])
        for label, controller in runs:
            with counted(f"{label}: cycles", unit="cycle") as step:
                _, pos, rot = simulate_cycles(
                    actual, controller, cube.poses, cycles, repeatability * 1e-6, seed, step
                )
            pc = pose_characteristics(cube.poses, pos, rot, cube.components)
            for line in pc.lines(f"{label} calibration (simulated, {cycles} cycles)"):
                say(line)
            report[label] = pc.to_dict()
    if json_out:
        atomic_write_text(json_out, json.dumps(report, indent=1) + "\n")
        say(f"wrote {json_out}")
    if as_json:
        click.echo(json.dumps(report))
