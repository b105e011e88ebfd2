"""Benchmark: an instrument calibration's fit and its σ check, now against a baseline.

Usage:
    OPENBLAS_NUM_THREADS=1 python scripts/bench_instruments.py [--repeats 5]
        [--baseline DIR --label REV]

A Stewart platform (``stewart_6ups``, its first preset) with errors uniform in
±1 mm / ±10 mrad (seed 1) read by the typical ballbar at 60 random workspace poses
(σ 10 µm, seed 0) — what ``pincal simulate --random 60 --instrument distance``
writes. Timed (CPU time, median of repeats, BLAS threads 1): one evaluation of the
joint residual model without and with its Jacobian, the joint fit
(``identify_instruments``) and the σ check ``pincal calibrate`` runs after it
(``instrument_uncertainty``: the curvature draws). With ``--baseline DIR`` (another
checkout, e.g. ``git worktree add --detach DIR REV``) the same worker runs there in
the same session and the table gives both columns and their ratio.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
from bench_core import median_time  # scripts/ is on the path of a script run from it

ROOT = Path(__file__).resolve().parents[1]


def worker(repeats: int) -> dict[str, float]:
    """Time the operations with the pincal importable from the working directory."""
    from threadpoolctl import threadpool_limits

    from pincal.identification import (
        default_instrument,
        identify_instruments,
        instrument_uncertainty,
    )
    from pincal.identification.problem._instrument_problem import InstrumentProblem
    from pincal.measure import simulate_instrument
    from pincal.model import load_mechanism, parameters, sample_actuators

    with threadpool_limits(1):
        nom = load_mechanism("stewart_6ups")
        ps = parameters(nom, next(iter(nom.presets)))
        bound = np.array([1e-3 if u == "m" else 1e-2 for u in ps.units])
        actual = ps.apply(nom, np.random.default_rng(1).uniform(-bound, bound))
        q = sample_actuators(nom, 60, np.random.default_rng(0))
        inst, theta, ids = default_instrument(nom, "distance", q, std=1e-5)
        data = simulate_instrument(actual, inst, theta, q, np.random.default_rng(0), ids=ids)
        fit = identify_instruments(nom, ps, [data])
        problem = InstrumentProblem(nom, ps, [data])
        x = np.asarray(fit.values, dtype=float)
        return {
            "evaluate": median_time(lambda: problem.evaluate(x, jacobian=False), 5 * repeats),
            "evaluate+J": median_time(lambda: problem.evaluate(x, jacobian=True), 5 * repeats),
            "joint fit": median_time(lambda: identify_instruments(nom, ps, [data]), repeats),
            "σ check": median_time(lambda: instrument_uncertainty(fit, nom, [data]), repeats),
        }


def _run(path: Path, repeats: int) -> dict[str, float]:
    out = subprocess.run([sys.executable, str(ROOT / "scripts" / "bench_instruments.py"),
                          "--worker", f"--repeats={repeats}"], cwd=path, check=True,
                         capture_output=True, text=True, env={"PYTHONPATH": str(path),
                         "OPENBLAS_NUM_THREADS": "1", "PATH": "/usr/bin:/bin"})  # fmt: skip
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--baseline", type=Path, help="another checkout to compare")
    ap.add_argument("--label", default="baseline", help="the baseline's column label")
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.worker:
        print(json.dumps(worker(a.repeats)))
        return
    now = _run(ROOT, a.repeats)
    old = _run(a.baseline, a.repeats) if a.baseline else None
    print(f"Stewart ballbar, 60 readings; CPU time, median of {a.repeats} repeats "
          f"({5 * a.repeats} for the evaluations); BLAS threads 1\n")  # fmt: skip
    head = f"{'operation':12s} {'now':>11s}"
    print(head + (f" {a.label:>11s} {a.label + '/now':>12s}" if old else ""))
    for key, t in now.items():
        line = f"{key:12s} {t * 1e3:8.1f} ms"
        if old:
            line += f" {old[key] * 1e3:8.1f} ms {old[key] / t:11.2f}×"
        print(line)


if __name__ == "__main__":
    main()
