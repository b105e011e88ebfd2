"""Benchmark: exchange selection of 18 poses by O1, with and without rank-k updates.

Synthetic candidate set: 4096 random identification-Jacobian blocks (6 rows,
42 parameters, as for the 42-parameter Stewart platform of seed 000), fixed
seed. Both variants start from the same random design and must select the same
poses; the table gives the median wall time over repeated runs.

Usage: python scripts/bench_design.py [--repeats 5] [--slow-repeats 3]
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from pincal.design import exchange


def _time_runs(J: np.ndarray, m: int, fast: bool, repeats: int, seed: int):
    times = []
    result = None
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = exchange(J, m, "O1", rng=seed, fast=fast)
        times.append(time.perf_counter() - t0)
    return statistics.median(times), result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--candidates", type=int, default=4096)
    parser.add_argument("--rows", type=int, default=6)
    parser.add_argument("--params", type=int, default=42)
    parser.add_argument("-m", "--poses", type=int, default=18)
    parser.add_argument("--repeats", type=int, default=5, help="runs with rank-k updates")
    parser.add_argument("--slow-repeats", type=int, default=3, help="runs recomputing all")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    rng = np.random.default_rng(args.seed)
    J = rng.standard_normal((args.candidates, args.rows, args.params))
    print(
        f"exchange O1: {args.candidates} candidates × ({args.rows}, {args.params}) blocks, "
        f"m = {args.poses}, seed {args.seed}"
    )
    exchange(J, args.poses, "O1", rng=args.seed + 1)  # warm-up (BLAS threads, caches)
    t_fast, fast = _time_runs(J, args.poses, True, args.repeats, args.seed + 1)
    t_slow, slow = _time_runs(J, args.poses, False, args.slow_repeats, args.seed + 1)
    same = np.array_equal(fast.indices, slow.indices)

    header = f"{'variant':<34} {'runs':>4} {'iter':>5} {'O1':>10} {'median [s]':>11} {'ratio':>7}"
    print(header)
    print("-" * len(header))
    for name, runs, res, t in (
        ("rank-k updates (fast=True)", args.repeats, fast, t_fast),
        ("recompute by SVD (fast=False)", args.slow_repeats, slow, t_slow),
    ):
        print(
            f"{name:<34} {runs:>4} {res.iterations:>5} {res.value:>10.5f} {t:>11.3f} "
            f"{t / t_fast:>7.1f}"
        )
    print(f"initial O1 {fast.history[0]:.5f} → {fast.value:.5f}; same selection: {same}")
    print(f"time per iteration with updates: {1e3 * t_fast / fast.iterations:.1f} ms")


if __name__ == "__main__":
    main()
