"""Study: out-of-family detection on simulated production fleets, through the command line.

Each fleet is drawn and calibrated by ``pincal fleet simulate MODEL --units N --seed S``
(its default planted faulty units: max(1, 3 % of N), each with every parameter of one
joint placement moved by ±``--shift`` production σ) and ``pincal fleet run --jobs J``.
A planted unit is detected when ``fleet.json`` flags it; any other flag is a false one.
Prints one row per seed and the totals, with each run's wall time and units per second.

    python scripts/studies/fleet_detection.py --model stewart_6ups --units 200 --seeds 0,1,2
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def _pincal(*args: str) -> None:
    subprocess.run([sys.executable, "-m", "pincal.cli", *args], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)  # fmt: skip


def fleet(model: str, units: int, seed: int, shift: float, jobs: int) -> tuple:
    """(planted, detected, false flags, refused or failed, run wall time [s]) of one fleet."""
    with tempfile.TemporaryDirectory() as tmp:
        sim, run = Path(tmp) / "sim", Path(tmp) / "run"
        _pincal("fleet", "simulate", model, "--units", str(units), "--seed", str(seed),
                "--shift", str(shift), "--out", str(sim))  # fmt: skip
        start = time.perf_counter()
        _pincal("fleet", "run", str(sim / "FLEET.yaml"), "--out", str(run), "--jobs", str(jobs))
        wall = time.perf_counter() - start
        planted = {p["id"] for p in json.loads((sim / "truth.json").read_text())["planted"]}
        summary = json.loads((run / "fleet.json").read_text())["summary"]
    flagged = set(summary["out_of_family_ids"])
    lost = summary["refused"] + summary["failed"]
    return len(planted), len(planted & flagged), len(flagged - planted), lost, wall


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", default="stewart_6ups")
    ap.add_argument("--units", type=int, default=200)
    ap.add_argument("--seeds", default="0,1,2")
    ap.add_argument("--shift", type=float, default=8.0, help="faulty part [production σ]")
    ap.add_argument("--jobs", type=int, default=2, help="fleet run's local processes")
    a = ap.parse_args()
    print(f"{a.model}: {a.units} units, planted parts moved by {a.shift:g} production σ")
    print("| seed | planted | detected | false flags | refused/failed | run wall | units/s |")
    print("|---|---|---|---|---|---|---|")
    total = [0, 0, 0, 0]
    for seed in (int(s) for s in a.seeds.split(",")):
        p, d, f, lost, wall = fleet(a.model, a.units, seed, a.shift, a.jobs)
        total = [t + v for t, v in zip(total, (p, d, f, lost), strict=True)]
        print(f"| {seed} | {p} | {d} | {f} | {lost} | {wall:.0f} s | {a.units / wall:.2f} |",
              flush=True)  # fmt: skip
    p, d, f, lost = total
    print(f"| all | {p} | {d} ({100 * d / max(p, 1):.0f} %) | {f} | {lost} | | |")


if __name__ == "__main__":
    main()
