"""Study: do the σ ``pincal calibrate`` writes for a pose fit cover the truth?

Usage:
    python scripts/studies/pose_coverage.py [--model stewart_6ups] [--poses random|designed]
        [--count 10] [--box 1] [--noise declared|estimated] [--seeds 0:40]
        [--jobs 2 | --scheduler local:2|tcp://HOST:PORT]
    python scripts/studies/pose_coverage.py --summarise FILE.jsonl ...

Per seed S (truths simulated by pincal's simulate path, as ``pincal simulate`` draws
them): an actual machine with the preset's errors uniform in ±1 mm / ±10 mrad (seed
1000 + S), measured at ``--count`` poses — random workspace poses (seed S) or one
design chosen by O1 from 300 random candidates (seed 0, the same for every draw); with
``--box F`` each command's offset from home's is scaled by F (a workspace F times as
wide around home: ill-conditioned for F ≪ 1) — with a laser-tracker noise of 0.01 mm /
0.02 mrad; the noise is declared to the fit or
estimated from its residuals (the file without its ``# noise:`` header). The fit is
``pincal.identify``; the covariance written is what ``pincal calibrate`` writes
(:func:`pincal.identification.check_uncertainty` without a bootstrap: the linear
covariance, inflated along the directions the linearity check finds non-linear).
With e the error of the identified parameters from the truth:

- ``d2k``, ``d2k_lin``: eᵀC⁻¹e / k with C the written / the linear covariance (≈ 1 when
  right; with estimated noise its expectation is ν/(ν − 2) for ν residual dof, the
  ``E[d²/k]`` of the summary);
- ``in2``: the share of parameters with |e| ≤ 2σ (nominal 95.4 %); ``in_t``: within
  ±t·σ, the interval the calibration states (t = z = 1.96 with declared noise);
- ``joint``: d² inside the stated joint 95 % region (χ²_k, or k·F_{k,ν} with estimated
  noise); ``joint_chi2``: inside χ²_k(0.95) whatever the noise;
- ``method``: the written covariance's method; ``s``: seconds for the draw.

One JSON line per seed, in seed order; ``--summarise`` prints one table row per file
(mean ± s.e.). The draws run through :class:`pincal.executor.Executor` (``--jobs`` local
processes or a Dask ``--scheduler``); each is seeded by its own S, so the lines (but
``s``) do not depend on either.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time

import numpy as np
from scipy import stats

N_CANDIDATES = 300
NOISE = {"position": 0.01, "orientation": 0.02}  # [mm, mrad]


def _design(nom, ps, count: int) -> np.ndarray:
    """``count`` poses chosen by O1 (noise-scaled) from random candidates (seed 0)."""
    from pincal.design import DesignScaling, candidate_set, select_poses

    rng = np.random.default_rng(0)
    cands = candidate_set(nom, ps, f"random:{N_CANDIDATES}", rng)
    scaling = DesignScaling("noise", position_std=1e-5, orientation_std=2e-5)
    return select_poses(cands, count, "O1", scaling, rng=rng).q_act


def draw(a: argparse.Namespace, seed: int, q_design: np.ndarray | None) -> dict:
    """One seeded draw (module documentation)."""
    import pincal
    from pincal.identification import check_uncertainty, pose_residual_model

    nom = pincal.load_mechanism(a.model)
    ps = pincal.parameters(nom, a.preset or next(iter(nom.presets)))
    bound = np.array([1e-3 if u == "m" else 1e-2 for u in ps.units])
    truth = np.random.default_rng(1000 + seed).uniform(-bound, bound)
    actual = ps.apply(nom, truth)
    rng = np.random.default_rng(seed)
    q = q_design if q_design is not None else pincal.sample_actuators(nom, a.count, rng)
    if a.box != 1.0:  # a small workspace: the commands' offsets from home scaled
        home = nom.actuators_of(nom.q_home)
        q = home + a.box * (q - home)
    t0 = time.perf_counter()
    meas = pincal.simulate_measurements(actual, q, NOISE, rng)
    declared = a.noise == "declared"
    if not declared:
        meas = dataclasses.replace(meas, noise=None)
    result = pincal.identify(nom, ps, meas)
    problem = pose_residual_model(result, nom, meas)
    assert problem is not None
    check = check_uncertainty(problem, result, declared=declared)
    free = np.asarray(result.identified)
    e = result.values - truth[free]
    k = int(e.size)
    C, W = np.asarray(result.covariance), np.asarray(check.result.covariance)
    iv = check.intervals
    assert iv is not None
    d2, d2_lin = float(e @ np.linalg.solve(W, e)), float(e @ np.linalg.solve(C, e))
    z = np.abs(e) / np.sqrt(np.diag(W))
    return {"seed": seed, "k": k, "dof": iv.dof, "method": check.method,
            "flagged": check.issue is not None, "d2k": d2 / k, "d2k_lin": d2_lin / k,
            "in2": float(np.mean(z <= 2.0)), "in_t": float(np.mean(z <= iv.each)),
            "each": iv.each, "joint": bool(d2 <= iv.joint),
            "joint_chi2": bool(d2 <= stats.chi2.ppf(0.95, k)),
            "s": round(time.perf_counter() - t0, 2)}  # fmt: skip


def summarise(path: str) -> str:
    """One table row: mean ± s.e. of d²/k (written, linear), ±2σ, ±t·σ, joint coverage."""
    rows = [json.loads(line) for line in open(path, encoding="utf-8")]
    n = len(rows)

    def mean(key: str) -> str:
        x = np.array([r[key] for r in rows], dtype=float)
        return f"{x.mean():.3g} ± {x.std(ddof=1) / np.sqrt(n):.2g}"

    def share(key: str) -> str:
        p = float(np.mean([r[key] for r in rows]))
        return f"{100 * p:.0f} ± {100 * np.sqrt(p * (1 - p) / n):.0f} %"

    dof = [r["dof"] for r in rows if r["dof"] is not None]
    flagged = sum(r["flagged"] for r in rows)
    # E[d²/k] = E[F_{k,ν}] = ν/(ν − 2) with an estimated scale on ν dof, at the median ν
    nu = float(np.median(dof)) if dof else np.inf
    expect = 1.0 if not dof else nu / (nu - 2) if nu > 2 else np.inf
    return " | ".join([
        path, f"{n} draws",
        f"ν {nu:.3g} ({min(dof):.2g}–{max(dof):.2g})" if dof else "ν —",
        f"E[d²/k] {expect:.3g}",
        f"flagged {flagged}", f"d²/k {mean('d2k')}", f"linear {mean('d2k_lin')}",
        f"±2σ {100 * np.mean([r['in2'] for r in rows]):.1f} %",
        f"±t·σ {100 * np.mean([r['in_t'] for r in rows]):.1f} %",
        f"joint {share('joint')}", f"χ² region {share('joint_chi2')}",
        f"{np.median([r['s'] for r in rows]):.2g} s/draw",
    ])  # fmt: skip


def _draw_item(item: tuple[argparse.Namespace, int, np.ndarray | None]) -> dict:
    """One draw as an executor item: ``draw(args, seed, q_design)``."""
    return draw(*item)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--summarise", nargs="+", metavar="FILE",
                    help="print one row per file of this script's output instead")  # fmt: skip
    ap.add_argument("--model", default="stewart_6ups")
    ap.add_argument("--preset", default=None)
    ap.add_argument("--poses", default="random", choices=("random", "designed"))
    ap.add_argument("--count", type=int, default=10)
    ap.add_argument("--box", type=float, default=1.0,
                    help="scale of the commands' offsets from home (< 1: a small, "
                         "ill-conditioned workspace)")  # fmt: skip
    ap.add_argument("--noise", default="declared", choices=("declared", "estimated"))
    ap.add_argument("--seeds", default="0:40", help="first:last (exclusive)")
    ap.add_argument("--jobs", type=int, default=1, help="local processes (default 1)")
    ap.add_argument("--scheduler", default=None,
                    help="a Dask scheduler: local:N or tcp://HOST:PORT")  # fmt: skip
    a = ap.parse_args()
    if a.summarise:
        print("\n".join(summarise(path) for path in a.summarise))
        return
    import pincal

    q_design = None
    if a.poses == "designed":
        nom = pincal.load_mechanism(a.model)
        q_design = _design(nom, pincal.parameters(nom, a.preset or next(iter(nom.presets))),
                           a.count)  # fmt: skip
    lo, hi = (int(v) for v in a.seeds.split(":"))
    from pincal.executor import Executor

    with Executor(a.scheduler, a.jobs) as ex:
        items = [(a, seed, q_design) for seed in range(lo, hi)]
        for rec in ex.map(_draw_item, items, progress="draws").values():
            print(json.dumps(rec), flush=True)


if __name__ == "__main__":
    main()
