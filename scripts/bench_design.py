"""Benchmark: exchange selection of 18 poses by O1, with and without rank-k updates.

Synthetic candidate set: 4096 random identification-Jacobian blocks (6 rows,
42 parameters, as for the 42-parameter Stewart platform of seed 000), fixed
seed. With ``--stewart`` the candidates are real: the bundled 6-UPS Stewart
platform's joint-space grid of 4 leg lengths per leg (4⁶ = 4096 rows) pushed
through the forward kinematics (all rows kept, no workspace filter), with the
stewart42 Jacobian blocks whitened by 0.01 mm / 0.01 mrad noise. Both variants
start from the same random design and must select the same poses; the table
gives the median wall time over repeated runs.

With ``--stewart`` the end-to-end line adds the candidate evaluation (FK and Jacobian
blocks of all 4096 rows, ``--n-jobs`` processes) to the exchange; wall and CPU seconds
are both printed (on a shared machine the CPU time is the stable figure). BLAS runs
single-threaded.

Usage: python scripts/bench_design.py [--stewart] [--n-jobs 1] [--repeats 5] [--slow-repeats 3]
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
    parser.add_argument(
        "--stewart", action="store_true", help="real Stewart 4-level joint grid (4096 poses)"
    )
    parser.add_argument("--levels", type=int, default=4, help="grid levels with --stewart")
    parser.add_argument("--n-jobs", type=int, default=1, help="processes for the candidates")
    args = parser.parse_args()
    from threadpoolctl import threadpool_limits

    threadpool_limits(1)
    t_cand = c_cand = 0.0

    if args.stewart:
        import pincal
        from pincal.design import DesignScaling, grid_candidates

        mech = pincal.load_mechanism("stewart_6ups")
        params = pincal.parameters(mech, "stewart42")
        grid_candidates(mech, params, 2, in_workspace=False)  # warm-up (caches, imports)
        t0, c0 = time.perf_counter(), time.process_time()
        cands = grid_candidates(mech, params, args.levels, in_workspace=False, n_jobs=args.n_jobs)
        t_cand, c_cand = time.perf_counter() - t0, time.process_time() - c0
        sc = DesignScaling(rows="noise", position_std=1e-5, orientation_std=1e-5)
        J = sc.apply(cands.jacobians, cands.components).J
        print(
            f"Stewart 6-UPS grid {args.levels}^6: {cands.summary()}; FK + Jacobian blocks "
            f"{t_cand:.2f} s wall, {c_cand:.2f} s CPU of this process ({args.n_jobs} "
            f"process(es)); {sc.describe()}"
        )
    else:
        rng = np.random.default_rng(args.seed)
        J = rng.standard_normal((args.candidates, args.rows, args.params))
    print(
        f"exchange O1: {J.shape[0]} candidates × ({J.shape[1]}, {J.shape[2]}) blocks, "
        f"m = {args.poses}, seed {args.seed}"
    )
    exchange(J, args.poses, "O1", rng=args.seed + 1)  # warm-up (BLAS threads, caches)
    c0 = time.process_time()
    t_fast, fast = _time_runs(J, args.poses, True, args.repeats, args.seed + 1)
    c_fast = (time.process_time() - c0) / max(1, args.repeats)
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
    if args.stewart:
        print(
            f"end to end, candidates + exchange: {t_cand + t_fast:.2f} s wall, "
            f"{c_cand + c_fast:.2f} s CPU (mean CPU per exchange run)"
        )


if __name__ == "__main__":
    main()
