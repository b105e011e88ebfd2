"""Units per second of `pincal fleet run`: local processes (joblib) vs Dask, 1 and 2 workers.

Usage: python scripts/bench_fleet.py [--units 6] [--repeats 3]

Each configuration calibrates the same simulated wedge3 fleet into a fresh directory
(nothing reused); the time includes starting the workers (and the Dask cluster). BLAS
runs on one thread (threadpoolctl) in this process and in every worker.

Memory: the peak resident set of this process before and after the in-process run
(``--jobs 1``, every unit calibrated here one after the other) and, per unit, the size of
a unit's summary the fleet run keeps (its identified values and covariance).
"""

from __future__ import annotations

import argparse
import resource
import statistics
import tempfile
import time
from pathlib import Path

from click.testing import CliRunner
from threadpoolctl import threadpool_limits

from pincal.cli import main

CONFIGS = [("joblib", ["--jobs", "1"]), ("joblib", ["--jobs", "2"]),
           ("dask", ["--scheduler", "local:1"]), ("dask", ["--scheduler", "local:2"])]  # fmt: skip


def _run(args):
    res = CliRunner().invoke(main, args, catch_exceptions=False)
    if res.exit_code != 0:
        raise SystemExit(res.output)


def main_() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--units", type=int, default=6)
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp, threadpool_limits(1):
        sim = Path(tmp) / "sim"
        _run(["fleet", "simulate", "wedge3", "--units", str(a.units), "--poses", "100",
              "--seed", "0", "--out", str(sim)])  # fmt: skip
        before, after = _peak_mb(), float("nan")
        print(f"| backend | workers | units/s (median of {a.repeats}) | s per unit |")
        print("|---|---|---|---|")
        for backend, opts in CONFIGS:
            times = []
            for r in range(a.repeats):
                out = Path(tmp) / f"{backend}{opts[-1].replace(':', '')}-{r}"
                t0 = time.perf_counter()
                _run(["fleet", "run", str(sim / "FLEET.yaml"), "--out", str(out), *opts])
                times.append(time.perf_counter() - t0)
            t = statistics.median(times)
            print(f"| {backend} | {opts[-1].split(':')[-1]} | {a.units / t:.2f} | "
                  f"{t / a.units:.2f} |", flush=True)  # fmt: skip
            if opts == ["--jobs", "1"]:
                after = _peak_mb()
        summaries = list((out / ".fleet-results").glob("*"))
        kept = sum(f.stat().st_size for f in summaries) / max(len(summaries), 1)
        print(f"\npeak resident memory of this process: {before:.0f} MB before, {after:.0f} MB "
              f"after calibrating {a.units} units in it (--jobs 1); a unit's kept result "
              f"{kept / 1024:.1f} KiB on disk")  # fmt: skip


def _peak_mb() -> float:
    """This process' peak resident set [MB] (Linux reports kilobytes)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


if __name__ == "__main__":
    main_()
