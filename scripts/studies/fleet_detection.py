"""Study: out-of-family detection on simulated production fleets, through the command line.

Each fleet is drawn and calibrated by ``pincal fleet simulate MODEL --units N --seed S``
(its default planted faulty units: max(1, 3 % of N), each with every parameter of one
joint placement moved by ±``--shift`` production σ) and ``pincal fleet run --jobs J``.
A planted unit is detected when ``fleet.json`` flags it; any other flag is a false one.
Prints one row per seed and the totals, with each run's wall time and units per second.

How visible a planted part is in the unit's own data: its noncentrality
``λ = δᵀ (C_u + diag τ²)⁻¹ δ`` (δ the part's shift over the compared parameters, C_u the
unit's covariance, τ the fleet's spread) gives the test's predicted power
``P(χ²(p, λ) > D_limit)``; the last table splits the planted units by that power.

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

import numpy as np
from scipy import stats

from pincal.workflow import unit_summary


def _pincal(*args: str) -> None:
    subprocess.run([sys.executable, "-m", "pincal.cli", *args], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)  # fmt: skip


def _power(run: Path, doc: dict, uid: str, shift: dict[str, float]) -> float:
    """The out-of-family test's predicted power for a planted unit (module doc)."""
    entry = next(u for u in doc["units"] if u["id"] == uid)
    if entry["status"] != "calibrated":
        return float("nan")
    unit = unit_summary(uid, run / entry["calibration"])
    assert unit is not None
    names = [p["name"] for p in doc["parameters"]]
    idx = [unit["names"].index(n) for n in names]
    C = np.asarray(unit["covariance"])[np.ix_(idx, idx)]
    tau = np.array([p["production_std"] for p in doc["parameters"]])
    delta = np.array([shift.get(n, 0.0) for n in names])
    lam = float(delta @ np.linalg.solve(C + np.diag(tau**2), delta))
    test = doc["test"]
    return float(stats.ncx2.sf(test["distance_threshold"], test["dof"], lam))


def fleet(model: str, units: int, seed: int, shift: float, jobs: int) -> tuple:
    """(planted, detected, false flags, refused or failed, run wall time [s], [(power,
    detected)] per planted unit) of one fleet."""
    with tempfile.TemporaryDirectory() as tmp:
        sim, run = Path(tmp) / "sim", Path(tmp) / "run"
        _pincal("fleet", "simulate", model, "--units", str(units), "--seed", str(seed),
                "--shift", str(shift), "--out", str(sim))  # fmt: skip
        start = time.perf_counter()
        _pincal("fleet", "run", str(sim / "FLEET.yaml"), "--out", str(run), "--jobs", str(jobs))
        wall = time.perf_counter() - start
        planted = json.loads((sim / "truth.json").read_text())["planted"]
        doc = json.loads((run / "fleet.json").read_text())
        flagged = set(doc["summary"]["out_of_family_ids"])
        powers = [(_power(run, doc, p["id"], p["parameters"]), p["id"] in flagged)
                  for p in planted]  # fmt: skip
    ids = {p["id"] for p in planted}
    lost = doc["summary"]["refused"] + doc["summary"]["failed"]
    return len(ids), len(ids & flagged), len(flagged - ids), lost, wall, powers


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
    total, powers = [0, 0, 0, 0], []
    for seed in (int(s) for s in a.seeds.split(",")):
        p, d, f, lost, wall, pw = fleet(a.model, a.units, seed, a.shift, a.jobs)
        total = [t + v for t, v in zip(total, (p, d, f, lost), strict=True)]
        powers += pw
        print(f"| {seed} | {p} | {d} | {f} | {lost} | {wall:.0f} s | {a.units / wall:.2f} |",
              flush=True)  # fmt: skip
    p, d, f, lost = total
    print(f"| all | {p} | {d} ({100 * d / max(p, 1):.0f} %) | {f} | {lost} | | |")
    print("\n| predicted power | planted | detected | mean predicted power |\n|---|---|---|---|")
    for name, lo, hi in (("≥ 0.95", 0.95, 1.01), ("0.05–0.95", 0.05, 0.95), ("< 0.05", 0, 0.05)):
        rows = [(w, hit) for w, hit in powers if lo <= w < hi]
        mean = f"{np.mean([w for w, _ in rows]):.2f}" if rows else "–"
        print(f"| {name} | {len(rows)} | {sum(h for _, h in rows)} | {mean} |")
    refused = sum(1 for w, _ in powers if np.isnan(w))
    print(f"(planted units the gate refused: {refused})")


if __name__ == "__main__":
    main()
