"""`pincal fleet`: simulate a production fleet, calibrate every unit, flag the odd ones."""

from __future__ import annotations

import json
from pathlib import Path

import click

from pincal.cli.common import fail_cleanly

SCHEDULER_HELP = (
    "Run the units on dask.distributed: local:N (a local cluster of N worker processes) "
    "or a scheduler address tcp://host:8786 (its workers must see the same file paths). "
    'Needs the optional extra: pip install "pincal[dask]". Default: local processes (--jobs).'
)


@click.group()
def fleet() -> None:
    """Fleets of units of one model: simulate one, calibrate every unit, compare them.

    Both subcommands take --json: a JSON summary on stdout instead of the text lines.

    \b
    Examples:
      pincal fleet simulate stewart_6ups --units 200 --seed 1 --out fleet/
      pincal fleet run fleet/FLEET.yaml --out fleet-report/ --jobs 2
      pincal fleet run fleet/FLEET.yaml --out fleet-report/ --scheduler local:2
    """


@fleet.command("simulate")
@click.argument("model")
@click.option(
    "--units",
    "n_units",
    type=click.IntRange(2, 100000),
    required=True,
    help="Units in the fleet (≥ 2).",
)
@click.option(
    "--out",
    required=True,
    type=click.Path(file_okay=False),
    help="New (or empty) directory: FLEET.yaml, truth.json, one folder per unit.",
)
@click.option(
    "--seed",
    type=click.IntRange(min=0),
    default=0,
    show_default=True,
    help="Seed of the fleet (geometry, planted units, poses, noise).",
)
@click.option("--params", "preset", default=None, help="Parameter preset (default: first).")
@click.option(
    "--poses",
    "n_poses",
    type=click.IntRange(10, 5000),
    default=40,
    show_default=True,
    help="Random poses measured per unit.",
)
@click.option(
    "--planted",
    type=click.IntRange(min=0),
    default=None,
    help="Out-of-family units (a faulty part each) [default: max(1, 3 % of units)].",
)
@click.option(
    "--spread",
    default="0.1,0.5",
    show_default=True,
    metavar="MM,MRAD",
    help="1σ production spread of lengths, angles.",
)
@click.option(
    "--shift",
    type=click.FloatRange(0, 100),
    default=8.0,
    show_default=True,
    help="A faulty part's shift, in production σ, on each parameter of one joint.",
)
@click.option(
    "--noise",
    default="0.01,0.02",
    show_default=True,
    metavar="MM,MRAD",
    help="Instrument noise 1σ (declared in each unit's file).",
)
@click.option("--json", "as_json", is_flag=True, help="Print a JSON summary on stdout.")
@fail_cleanly
def simulate(
    model: str,
    n_units: int,
    out: str,
    seed: int,
    preset: str | None,
    n_poses: int,
    planted: int | None,
    spread: str,
    shift: float,
    noise: str,
    as_json: bool,
) -> None:
    """Draw a seeded fleet of MODEL and simulate each unit's measurement file.

    Every unit shares the line's offset of the nominal geometry plus its own Gaussian
    production spread; a few planted units carry a faulty part (every parameter of one
    joint moved by --shift production σ), listed in truth.json. FLEET.yaml lists the
    units for `pincal fleet run`.
    """
    from tqdm import tqdm

    from pincal import __version__
    from pincal.cli._limits import number_pair
    from pincal.errors import OutputPathError
    from pincal.io import atomic_write_text, fleet_text, write_measurements
    from pincal.measure import NoiseModel
    from pincal.model import load_mechanism
    from pincal.sensitivity import parameters
    from pincal.workflow import draw_fleet, simulate_unit

    s_mm, s_mrad = number_pair(spread, "--spread", form="mm,mrad", bounds=(0.0, 100.0))
    n_mm, n_mrad = number_pair(noise, "--noise", form="mm,mrad", bounds=(0.0, 100.0))
    root = Path(out)
    if root.exists() and (not root.is_dir() or any(root.iterdir())):
        raise OutputPathError(
            f"--out {out} exists and is not an empty directory: give a new directory for the fleet"
        )
    nominal = load_mechanism(model)
    preset = preset or next(iter(nominal.presets), "full")
    params = parameters(nominal, preset)
    draw = draw_fleet(
        params, n_units, seed, spread_mm=s_mm, spread_mrad=s_mrad, planted=planted, shift=shift
    )
    ids = [f"SN-{i + 1:04d}" for i in range(n_units)]
    root.mkdir(parents=True, exist_ok=True)
    units = []
    for i in tqdm(range(n_units), desc="simulating units", leave=False, disable=None):
        meas = simulate_unit(
            nominal, params, draw.values[i], n_poses, NoiseModel(n_mm, n_mrad), draw.seeds[i]
        )
        write_measurements(root / ids[i] / "measurements.csv", meas)
        units.append({"id": ids[i], "data": f"{ids[i]}/measurements.csv"})
    truth = {
        "written_by": f"pincal {__version__}",
        "model": model,
        "preset": preset,
        "seed": seed,
        "poses_per_unit": n_poses,
        "spread_mm_mrad": [s_mm, s_mrad],
        "shift_sigma": shift,
        "noise_mm_mrad": [n_mm, n_mrad],
        "names": list(draw.names),
        "offset": draw.offset.tolist(),
        "planted": [{"id": ids[i], "parameters": p} for i, p in sorted(draw.planted.items())],
        "units": [{"id": ids[i], "values": draw.values[i].tolist()} for i in range(n_units)],
    }
    atomic_write_text(root / "truth.json", json.dumps(truth, indent=1) + "\n")
    atomic_write_text(root / "FLEET.yaml", fleet_text(model, units, preset))
    planted_ids = ", ".join(p["id"] for p in truth["planted"]) or "none"
    if as_json:
        click.echo(
            json.dumps(
                {
                    "fleet": str(root / "FLEET.yaml"),
                    "truth": str(root / "truth.json"),
                    "units": n_units,
                    "planted": [p["id"] for p in truth["planted"]],
                }
            )
        )
        return
    click.echo(
        f"wrote {root / 'FLEET.yaml'} ({n_units} units of {model}, preset {preset}; "
        f"planted out-of-family: {planted_ids}) and {root / 'truth.json'}"
    )


@fleet.command("run")
@click.argument("fleet_file", type=click.Path(dir_okay=False))
@click.option(
    "--out",
    required=True,
    type=click.Path(file_okay=False),
    help="Report directory: units/<id>/ (calibration directories), fleet.json, "
    "fleet.md, fleet.html, fleet_parameters.png.",
)
@click.option("--scheduler", default=None, metavar="local:N|tcp://HOST:PORT", help=SCHEDULER_HELP)
@click.option(
    "--jobs",
    "n_jobs",
    type=click.IntRange(min=-1),
    default=1,
    show_default=True,
    help="Local processes without --scheduler (-1: every CPU).",
)
@click.option(
    "--method",
    default="gauss-newton",
    show_default=True,
    help="Identification solver of every unit.",
)
@click.option(
    "--alpha",
    type=click.FloatRange(0, 1, min_open=True, max_open=True),
    default=0.01,
    show_default=True,
    help="Fleet-wise false-alarm rate of the out-of-family test "
    "(Bonferroni: each unit at alpha / units).",
)
@click.option("--json", "as_json", is_flag=True, help="Print fleet.json's summary on stdout.")
@fail_cleanly
def run(
    fleet_file: str,
    out: str,
    scheduler: str | None,
    n_jobs: int,
    method: str,
    alpha: float,
    as_json: bool,
) -> None:
    """Calibrate every unit of FLEET_FILE and report the fleet.

    Each unit is calibrated by `pincal calibrate` into OUT/units/<id>/ (its output in
    OUT/logs/<id>.log). A rerun skips every unit already done (results are kept per unit
    as they arrive; a unit whose calibration directory is complete is read back). Units
    the quality gate refuses are listed, not compared; a unit that fails is reported and
    the others go on. fleet.json lists every unit {id, status, out_of_family, distance,
    p_value, …}; fleet.md / fleet.html show the test and the per-parameter spread.
    """
    from pincal.cli._fleet_doc import fleet_document
    from pincal.cli._fleet_unit import calibrate_unit, file_digest
    from pincal.errors import PincalError
    from pincal.executor import Executor
    from pincal.io import ResultStore, atomic_write_text, read_fleet
    from pincal.report import fleet_html, fleet_markdown, plot_fleet
    from pincal.workflow import UnitEstimate, fleet_statistics

    spec = read_fleet(fleet_file)
    root = Path(out).resolve()
    items = [
        (
            spec.model,
            spec.preset,
            u.id,
            str(u.data.resolve()),
            str(root / "units" / u.id),
            method,
            str(root / "logs" / f"{u.id}.log"),
        )
        for u in spec.units
    ]
    keys = [f"{u.id}.{file_digest(u.data)[:16]}" for u in spec.units]
    root.mkdir(parents=True, exist_ok=True)
    with Executor(scheduler, n_jobs) as ex:
        results = ex.map(
            calibrate_unit,
            items,
            keys=keys,
            store=ResultStore(root / ".fleet-results"),
            progress="calibrating units",
        )
    import numpy as np

    done = [r.value for r in results if r.ok and r.value["status"] == "calibrated"]
    estimates = [
        UnitEstimate(s["id"], tuple(s["names"]), np.array(s["values"]), np.array(s["covariance"]))
        for s in done
    ]
    stats = None
    if len(estimates) >= 3:
        try:
            stats = fleet_statistics(estimates, alpha)
        except PincalError as exc:
            click.echo(f"pincal: warning: no out-of-family test: {exc}", err=True)
    doc = fleet_document(spec, results, stats, alpha, "units")
    atomic_write_text(root / "fleet.json", json.dumps(doc, indent=1) + "\n")
    if doc["parameters"]:
        plot_fleet(doc, root / "fleet_parameters.png")
    atomic_write_text(root / "fleet.md", fleet_markdown(doc))
    atomic_write_text(root / "fleet.html", fleet_html(doc))
    s = doc["summary"]
    if as_json:
        click.echo(json.dumps({"report": str(root / "fleet.json"), **s}))
        return
    reused = sum(bool(u.get("reused")) for u in doc["units"])
    click.echo(
        f"{s['calibrated']} of {s['units']} units calibrated ({reused} read back), "
        f"{s['refused']} refused by the gate, {s['failed']} failed"
    )
    for u in doc["units"]:
        if u["status"] != "calibrated" or u.get("out_of_family"):
            what = "out of family" if u.get("out_of_family") else u["status"]
            why = f"p = {u['p_value']:.2g}" if u.get("out_of_family") else u.get("reason")
            click.echo(f"  {u['id']}: {what} ({why})")
    click.echo(f"wrote {root}/fleet.json, fleet.md, fleet.html (calibrations in {root}/units/)")
