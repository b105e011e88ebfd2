"""Study: drift between two calibrations of a unit — detection and false drifts.

Each fleet is drawn and calibrated by the command line itself (``pincal fleet simulate
MODEL --recalibrated N --drifted D --shift S``, then ``pincal fleet run``): every unit
is measured in two sessions, D of them with one part moved by ±S production σ between
the sessions (every parameter of one joint placement). A drifted unit is caught when
``fleet.json`` names it; a false drift is a named unit whose parts did not move.

    python scripts/studies/fleet_drift.py --model wedge3 --shifts 2,4,8 --seeds 0,1,2
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path


def _pincal(*args: str) -> None:
    subprocess.run([sys.executable, "-m", "pincal.cli", *args], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)  # fmt: skip


def fleet(model: str, units: int, drifted: int, shift: float, seed: int, poses: int):
    """(drifted, caught, in-family comparisons, false drifts) of one simulated fleet."""
    with tempfile.TemporaryDirectory() as tmp:
        sim, run = Path(tmp) / "sim", Path(tmp) / "run"
        _pincal("fleet", "simulate", model, "--units", str(units), "--recalibrated",
                str(units), "--drifted", str(drifted), "--shift", str(shift), "--poses",
                str(poses), "--seed", str(seed), "--out", str(sim))  # fmt: skip
        _pincal("fleet", "run", str(sim / "FLEET.yaml"), "--out", str(run))
        truth = json.loads((sim / "truth.json").read_text())
        doc = json.loads((run / "fleet.json").read_text())
    moved = {r["id"] for r in truth["recalibrated"] if r["drift"]}
    named = set(doc["summary"]["drifted_ids"])
    return (
        len(moved),
        len(moved & named),
        doc["summary"]["drift_compared"] - len(moved),
        len(named - moved),
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", default="wedge3")
    ap.add_argument("--units", type=int, default=20, help="units, each measured twice")
    ap.add_argument("--drifted", type=int, default=5)
    ap.add_argument("--shifts", default="2,4,8", help="drift sizes [production σ]")
    ap.add_argument("--seeds", default="0,1,2")
    ap.add_argument("--poses", type=int, default=100)
    a = ap.parse_args()
    print(f"{a.model}: {a.units} units measured twice, {a.drifted} with a part moved")
    print("| shift [production σ] | fleets | drifted caught | false drifts (in-family pairs) |")
    print("|---|---|---|---|")
    for shift in (float(s) for s in a.shifts.split(",")):
        totals = [0, 0, 0, 0]
        seeds = [int(s) for s in a.seeds.split(",")]
        for seed in seeds:
            for k, v in enumerate(fleet(a.model, a.units, a.drifted, shift, seed, a.poses)):
                totals[k] += v
        d, c, n, f = totals
        print(f"| {shift:g} | {len(seeds)} | {c} of {d} | {f} of {n} |", flush=True)


if __name__ == "__main__":
    main()
