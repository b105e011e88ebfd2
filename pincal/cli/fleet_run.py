"""`pincal fleet run`: calibrate every unit of a fleet file and report the fleet."""

from __future__ import annotations

import json
from pathlib import Path

import click

from pincal.cli.common import fail_cleanly, jobs_option, scheduler_option


@click.command("run")
@click.argument("fleet_file", type=click.Path(dir_okay=False))
@click.option("--out", required=True, type=click.Path(file_okay=False),
              help="Report directory: units/<id>/ (calibration directories), fleet.json, "
              "fleet.md, fleet.html, fleet_parameters.png.")  # fmt: skip
@scheduler_option("the units")
@jobs_option("Local processes without --scheduler (-1: every CPU).")
@click.option("--method", default="gauss-newton", show_default=True,
              help="Identification solver of every unit.")  # fmt: skip
@click.option("--alpha", type=click.FloatRange(0, 1, min_open=True, max_open=True), default=0.01,
              show_default=True, help="Fleet-wise false-alarm rate of the out-of-family test "
              "(Bonferroni: each unit at alpha / units).")  # fmt: skip
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
    OUT/logs/<id>.log); a unit listed once per session (each with its date:) into
    OUT/units/<id>@<date>/, its consecutive sessions compared for drift. A rerun skips
    every unit already done (results are kept per unit as they arrive; a unit whose
    calibration directory is complete is read back). Units the quality gate refuses are
    listed, not compared; a unit that fails is reported and the others go on.
    fleet.json lists every unit {id, status, out_of_family, distance, p_value, …} and
    the drift of recalibrated units; fleet.md / fleet.html show the tests and the
    per-parameter spread.
    """
    from pincal.cli._fleet_unit import calibrate_unit
    from pincal.executor import Executor
    from pincal.io import ResultStore, atomic_write_text, read_fleet
    from pincal.report import fleet_html, fleet_markdown, plot_fleet
    from pincal.workflow import fleet_jobs, fleet_report

    spec = read_fleet(fleet_file)
    root = Path(out).resolve()
    items, keys = fleet_jobs(spec, root, method)
    root.mkdir(parents=True, exist_ok=True)
    with Executor(scheduler, n_jobs) as ex:
        store = ResultStore(root / ".fleet-results")
        results = ex.map(calibrate_unit, items, keys=keys, store=store,
                         progress="calibrating units")  # fmt: skip
    judged = fleet_report(spec, results, alpha, "units")
    if judged.warning is not None:
        click.echo(f"pincal: warning: no out-of-family test: {judged.warning}", err=True)
    doc = judged.document
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
    ids = len({u["id"] for u in doc["units"]})
    what = "units" if ids == s["units"] else f"sessions of {ids} units"
    click.echo(
        f"{s['calibrated']} of {s['units']} {what} calibrated ({reused} read back), "
        f"{s['refused']} refused by the gate, {s['failed']} failed"
    )
    for u in doc["units"]:
        if u["status"] != "calibrated" or u.get("out_of_family"):
            what = "out of family" if u.get("out_of_family") else u["status"]
            why = f"p = {u['p_value']:.2g}" if u.get("out_of_family") else u.get("reason")
            click.echo(f"  {u.get('session', u['id'])}: {what} ({why})")
    if doc["drift"]:
        click.echo(f"{s['drifted']} of {s['drift_compared']} recalibrations drifted")
    for d in doc["drift"]:
        if d["drifted"]:
            moved = ", ".join(f"{x['name']} {x['z']:+.1f}σ" for x in d["largest"])
            click.echo(f"  {d['id']}: drifted {d['before']} → {d['after']} "
                       f"(p = {d['p_value']:.2g}; {moved})")  # fmt: skip
    click.echo(f"wrote {root}/fleet.json, fleet.md, fleet.html (calibrations in {root}/units/)")
