"""Study: the fleet's out-of-family test on small fleets — its false-alarm rate against M.

Fleets with NO faulty unit are drawn from the test's own model (centre 0, production
spread τ_j ~ U(0.1, 1), each unit's estimation covariance C_u a random SPD matrix of
σ ~ U(0.05, 1) and correlations), so every flag is a false alarm; the test promises at
most ``alpha`` = 1 % of fleets with one or more flags. The centre and τ are estimated
from the units themselves, so on few units the χ²(p) reference does not hold.

    python scripts/studies/fleet_small.py --fleets 200 --params 30
"""

from __future__ import annotations

import argparse
import math
import sys

import numpy as np

from pincal.workflow import UnitEstimate, fleet_statistics


def _fleet(M: int, p: int, rng: np.random.Generator) -> list[UnitEstimate]:
    tau = rng.uniform(0.1, 1.0, p)
    names = tuple(f"q{j}" for j in range(p))
    units = []
    for u in range(M):
        A = rng.standard_normal((p, p))
        Q, _ = np.linalg.qr(A)
        s = rng.uniform(0.05, 1.0, p)
        C = (Q * s**2) @ Q.T
        x = tau * rng.standard_normal(p) + np.linalg.cholesky(C) @ rng.standard_normal(p)
        units.append(UnitEstimate(f"U{u}", names, x, C))
    return units


def false_alarms(M: int, p: int, fleets: int, seed: int) -> tuple[int, int]:
    """(fleets with one or more flags, fleets) over ``fleets`` fault-free fleets."""
    rng = np.random.default_rng(seed)
    flagged = 0
    for _ in range(fleets):
        stats = fleet_statistics(_fleet(M, p, rng))
        flagged += any(v.out_of_family for v in stats.units)
    return flagged, fleets


def main(argv: list[str] | None = None) -> int:
    """Print the false-alarm table (one row per fleet size)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fleets", type=int, default=200, help="fault-free fleets per size")
    ap.add_argument("--params", type=int, default=30, help="parameters per unit")
    ap.add_argument("--sizes", default="3,4,6,8,10,15,20,40", help="fleet sizes M")
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args(argv)
    print(f"# fault-free fleets, {a.params} parameters, {a.fleets} fleets per size, alpha 1 %")
    print("| M units | fleets with a flag | rate ± s.e. |")
    print("|---|---|---|")
    for M in (int(s) for s in a.sizes.split(",")):
        k, n = false_alarms(M, a.params, a.fleets, a.seed + M)
        r = k / n
        print(f"| {M} | {k}/{n} | {100 * r:.1f} % ± {100 * math.sqrt(r * (1 - r) / n):.1f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
