"""`pincal fleet simulate`: draw a seeded fleet and simulate each unit's measurement file."""

from __future__ import annotations

import json
from pathlib import Path

import click

from pincal.cli.common import fail_cleanly


@click.command("simulate")
@click.argument("model")
@click.option("--units", "n_units", type=click.IntRange(2, 100000), required=True,
              help="Units in the fleet (≥ 2).")  # fmt: skip
@click.option(
    "--out",
    required=True,
    type=click.Path(file_okay=False),
    help="New (or empty) directory: FLEET.yaml, truth.json, one folder per unit.",
)
@click.option("--seed", type=click.IntRange(min=0), default=0, show_default=True,
              help="Seed of the fleet (geometry, planted units, poses, noise).")  # fmt: skip
@click.option("--params", "preset", default=None, help="Parameter preset (default: first).")
@click.option("--poses", "n_poses", type=click.IntRange(10, 5000), default=40, show_default=True,
              help="Random poses measured per unit.")  # fmt: skip
@click.option(
    "--planted",
    type=click.IntRange(min=0),
    default=None,
    help="Out-of-family units (a faulty part each) [default: max(1, 3 % of units)].",
)
@click.option("--spread", default="0.1,0.5", show_default=True, metavar="MM,MRAD",
              help="1σ production spread of lengths, angles.")  # fmt: skip
@click.option(
    "--shift",
    type=click.FloatRange(0, 100),
    default=8.0,
    show_default=True,
    help="A faulty part's shift, in production σ, on each parameter of one joint.",
)
@click.option("--recalibrated", type=click.IntRange(min=0), default=0, show_default=True,
              help="Units measured again in a second session (dated after the first).")  # fmt: skip
@click.option("--drifted", type=click.IntRange(min=0), default=0, show_default=True,
              help="Of the recalibrated units, those with a part moved by --shift between "
              "the sessions (listed in truth.json).")  # fmt: skip
@click.option("--noise", default="0.01,0.02", show_default=True, metavar="MM,MRAD",
              help="Instrument noise 1σ (declared in each unit's file).")  # fmt: skip
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
    recalibrated: int,
    drifted: int,
    noise: str,
    as_json: bool,
) -> None:
    """Draw a seeded fleet of MODEL and simulate each unit's measurement file.

    Every unit shares the line's offset of the nominal geometry plus its own Gaussian
    production spread; a few planted units carry a faulty part (every parameter of one
    joint moved by --shift production σ), listed in truth.json. FLEET.yaml lists the
    units for `pincal fleet run`. --recalibrated units appear twice, dated 2026-01-15
    (ID/measurements.csv) and 2026-07-15 (ID/recalibration.csv, new poses and noise);
    `fleet run` compares their sessions for drift.
    """
    from tqdm import tqdm

    from pincal import __version__
    from pincal.cli._limits import number_pair
    from pincal.errors import OutputPathError
    from pincal.io import atomic_write_text, fleet_text, write_measurements
    from pincal.workflow import plan_fleet

    spread_pair = number_pair(spread, "--spread", form="mm,mrad", bounds=(0.0, 100.0))
    noise_pair = number_pair(noise, "--noise", form="mm,mrad", bounds=(0.0, 100.0))
    root = Path(out)
    if root.exists() and (not root.is_dir() or any(root.iterdir())):
        raise OutputPathError(
            f"--out {out} exists and is not an empty directory: give a new directory for the fleet"
        )
    plan = plan_fleet(model, n_units, seed, preset=preset, n_poses=n_poses, planted=planted,
                      spread=spread_pair, shift=shift, noise=noise_pair,
                      recalibrated=recalibrated, drifted=drifted)  # fmt: skip
    root.mkdir(parents=True, exist_ok=True)
    units = []
    for i in tqdm(range(n_units), desc="simulating units", leave=False, disable=None):
        for entry, second in plan.sessions(i):
            write_measurements(root / entry["data"], plan.measurements(i, second))
            units.append(entry)
    truth = {"written_by": f"pincal {__version__}", **plan.truth()}
    atomic_write_text(root / "truth.json", json.dumps(truth, indent=1) + "\n")
    atomic_write_text(root / "FLEET.yaml", fleet_text(model, units, plan.preset))
    planted_ids = [p["id"] for p in truth["planted"]]
    drifted_ids = [r["id"] for r in truth["recalibrated"] if r["drift"]]
    if as_json:
        click.echo(json.dumps({"fleet": str(root / "FLEET.yaml"),
                               "truth": str(root / "truth.json"), "units": n_units,
                               "planted": planted_ids, "recalibrated": len(plan.draw.second),
                               "drifted": drifted_ids}))  # fmt: skip
        return
    again = (
        f"; recalibrated {len(plan.draw.second)}, drifted: {', '.join(drifted_ids) or 'none'}"
        if plan.draw.second
        else ""
    )
    click.echo(
        f"wrote {root / 'FLEET.yaml'} ({n_units} units of {model}, preset {plan.preset}; "
        f"planted out-of-family: {', '.join(planted_ids) or 'none'}{again}) and "
        f"{root / 'truth.json'}"
    )
