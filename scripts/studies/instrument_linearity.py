"""Study: are the σ of an instrument fit right? d²/k and the curvature check, per draw.

Usage:
    python scripts/studies/instrument_linearity.py [--poses random|designed] [--std 1e-5]
        [--size 1,10] [--seeds 0:30] [--boot 0] [--model stewart_6ups] [--kind distance]
    python scripts/studies/instrument_linearity.py --summarise random.jsonl ...

Per seed S: an actual machine with errors uniform in ±size (mm, mrad; seed 1000 + S),
60 poses — random workspace poses (what ``pincal simulate --random 60 --instrument
KIND`` measures; seed S) or 60 chosen by exchange (O1) from 200 candidates on the
instrument's sphere — the kind's typical set-up read with σ = --std [m], and two joint
fits from the nominal model: of the noisy readings and of the same readings without
noise. Their difference is the error the fit's covariance describes (the noise-free
fit is the fit's target: what the data identify of the machine, gauge held alike), so

- ``d2k``: (x̂ − x̂₀)ᵀ C⁻¹ (x̂ − x̂₀) / k with C the linearised covariance (≈ 1 when right);
- ``zdiag``: mean over the parameters of (x̂ − x̂₀)²/σ² (per-parameter σ);
- ``d2k_dirs``: the same along the 12 largest-σ principal directions;
- ``excess``: the curvature check of ``pincal calibrate``
  (:func:`pincal.identification.uncertainty._linearity.check_curvature`, 64 draws), the d²/k the
  fit's second-order error adds (predicted from the fit alone);
- ``ratio_max``, ``jacobian_change``: the cost-ratio check of pose fits
  (:func:`pincal.identification.uncertainty._linearity.check_linearity`);
- ``widened``, ``d2k_s``, ``zdiag_s``, ``cover_s``: what ``pincal calibrate`` writes —
  :func:`pincal.identification.instrument_uncertainty` adds the second moment of the
  fit's second-order error (its own curvature draws) to the covariance: the largest σ
  ratio over combinations, d²/k, the per-parameter z², and whether d² lies inside the
  joint 95 % region χ²_k(0.95) (``cover``: the same with the linear covariance);
- with ``--boot B``: ``zdiag_b``, the per-parameter z² with the σ of a B-refit parametric
  bootstrap (what ``pincal calibrate --bootstrap B`` reports beside the σ; its sample
  covariance is not inverted), and ``boot_ratio_max``, its largest σ over the linear σ.

One JSON line per seed; ``--summarise FILE...`` turns such files into table rows
(:func:`summarise`).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time

import numpy as np
from scipy import stats

from pincal.design import select_poses
from pincal.identification import (
    default_instrument,
    identify_instruments,
    instrument_candidates,
    instrument_uncertainty,
)
from pincal.identification.problem._instrument_problem import InstrumentProblem
from pincal.identification.uncertainty._bootstrap import bootstrap_covariance
from pincal.identification.uncertainty._linearity import check_linearity
from pincal.measure import simulate_instrument
from pincal.model import load_mechanism, parameters, sample_actuators
from pincal.sensitivity import analyse_jacobian


def designed_rows(nom, ps, inst, theta, seed: int, count: int = 60) -> np.ndarray:
    """``count`` poses chosen by exchange (O1) from 200 candidates on the instrument's sphere."""
    n = len(ps)
    cands = instrument_candidates(nom, ps, inst, theta, 200, rng=seed, max_tilt=0.1)
    J = cands.jacobians[:, 0, :]
    order = np.r_[np.arange(n, J.shape[1]), np.arange(n)]
    ident = analyse_jacobian(J[:, order], tuple(cands.param_names[i] for i in order))
    base = np.sort(order[ident.base])
    sub = dataclasses.replace(cands, jacobians=cands.jacobians[:, :, base],
                              param_names=tuple(cands.param_names[i] for i in base))  # fmt: skip
    return cands.q_act[select_poses(sub, count, "O1", rng=seed).indices]


def draw(a: argparse.Namespace, nom, ps, seed: int) -> dict:
    """One seeded draw (see the module documentation)."""
    mm, mrad = (float(v) for v in a.size.split(","))
    bound = np.array([mm * 1e-3 if u == "m" else mrad * 1e-3 for u in ps.units])
    actual = ps.apply(nom, np.random.default_rng(1000 + seed).uniform(-bound, bound))
    rng = np.random.default_rng(seed)
    q = sample_actuators(nom, 60, np.random.default_rng(seed))
    inst, theta, ids = default_instrument(nom, a.kind, q, std=a.std)
    if a.poses == "designed":
        q = designed_rows(nom, ps, inst, theta, seed)
    data = simulate_instrument(actual, inst, theta, q, rng, ids=ids)
    exact = simulate_instrument(actual, inst, theta, q, noise=False, ids=ids).values
    fit = identify_instruments(nom, ps, [data])
    fit0 = identify_instruments(nom, ps, [dataclasses.replace(data, values=exact)])
    rec: dict = {"seed": seed, "poses": a.poses, "std": a.std, "k": int(fit.fitted.size),
                 "ok": bool(fit.result.success and fit0.result.success),
                 "same_free": bool(np.array_equal(fit.fitted, fit0.fitted))}  # fmt: skip
    if not rec["same_free"]:
        return rec
    problem = InstrumentProblem(nom, ps, [data])
    check = instrument_uncertainty(fit, nom, [data], seed=seed)  # what calibrate runs
    cu = check.curvature
    assert cu is not None and cu.second_moment is not None
    delta = (fit.values - fit0.values)[fit.fitted]
    C, k = fit.covariance, delta.size
    _, s, Vt = np.linalg.svd(problem.evaluate(fit.values)[1][:, fit.fitted], full_matrices=False)
    top = Vt[np.argsort(s)[:12]]  # the 12 largest-σ directions
    z_top = (top @ delta) * np.sort(s)[:12]
    lin = check_linearity(problem, fit.values, fit.fitted)
    rec |= {"excess": cu.excess, "excess_se": cu.excess_se,
            "ratio_max": float(np.nanmax(lin.ratio)), "jacobian_change": lin.worst()[1],
            "d2k": float(delta @ np.linalg.solve(C, delta)) / k,
            "zdiag": float(np.mean(delta**2 / np.diag(C))),
            "d2k_dirs": float(np.mean(z_top**2))}  # fmt: skip
    W = C + cu.second_moment  # what pincal calibrate writes (over all the unknowns)
    d2w, limit = float(delta @ np.linalg.solve(W, delta)), float(stats.chi2.ppf(0.95, k))
    rec |= {"widened": check.widened, "d2k_s": d2w / k,
            "zdiag_s": float(np.mean(delta**2 / np.diag(W))),
            "cover": bool(rec["d2k"] * k <= limit), "cover_s": bool(d2w <= limit)}  # fmt: skip
    if a.boot:
        boot = bootstrap_covariance(problem, fit.values, fit.fitted, draws=a.boot, seed=0)
        sb2 = np.diag(boot.covariance)
        rec |= {"boot_draws": boot.draws, "boot_failed": boot.failed,
                "zdiag_b": float(np.mean(delta**2 / sb2)),
                "boot_ratio_max": float(np.max(np.sqrt(sb2 / np.diag(C))))}  # fmt: skip
    return rec


def summarise(path: str) -> str:
    """One table row from a file of the JSON lines above (draws whose gauge differed left out).

    Mean ± standard error (median) of d²/k and of the per-parameter z²; the share of
    draws whose error lies inside the joint 95 % region, ± its binomial standard error;
    for the linear covariance, the one ``pincal calibrate`` writes (second-order term
    added) and a uniform factor 1 + excess on every σ² (for comparison).
    """
    recs = [json.loads(line) for line in open(path, encoding="utf-8")]
    rows = [r for r in recs if "d2k" in r]
    n = len(rows)
    keys = ("d2k", "d2k_s", "zdiag", "zdiag_s", "cover", "cover_s", "excess", "k")
    v = {key: np.array([r[key] for r in rows], dtype=float) for key in keys}
    f = 1.0 + np.where(v["excess"] > 1.0, v["excess"], 0.0)
    v |= {"d2k_f": v["d2k"] / f, "zdiag_f": v["zdiag"] / f,
          "cover_f": v["d2k"] * v["k"] / f <= stats.chi2.ppf(0.95, v["k"])}  # fmt: skip

    def mean(x: np.ndarray) -> str:
        return f"{x.mean():.3g} ± {x.std(ddof=1) / np.sqrt(n):.2g} ({np.median(x):.3g})"

    def share(x: np.ndarray) -> str:
        p = float(np.mean(x))
        return f"{100 * p:.0f} ± {100 * np.sqrt(p * (1 - p) / n):.0f} %"

    e = v["excess"]
    return " | ".join([
        f"{path}: {n} of {len(recs)} draws", f"excess {e.min():.2g}–{e.max():.2g} "
        f"({np.median(e):.2g})",
        *(f"{name}: d²/k {mean(v['d2k' + s])}, z² {mean(v['zdiag' + s])}, covers "
          f"{share(v['cover' + s])}"
          for name, s in (("linear", ""), ("written", "_s"), ("factor", "_f"))),
    ])  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--summarise", nargs="+", metavar="FILE",
                    help="print one row per file of this script's output instead")  # fmt: skip
    ap.add_argument("--model", default="stewart_6ups")
    ap.add_argument("--preset", default=None)
    ap.add_argument("--kind", default="distance")
    ap.add_argument("--poses", default="random", choices=("random", "designed"))
    ap.add_argument("--std", type=float, default=1e-5, help="reading σ [m]")
    ap.add_argument("--size", default="1,10", help="error bounds 'mm,mrad'")
    ap.add_argument("--seeds", default="0:30", help="first:last (exclusive)")
    ap.add_argument("--boot", type=int, default=0, help="bootstrap refits (0: none)")
    a = ap.parse_args()
    if a.summarise:
        print("\n".join(summarise(path) for path in a.summarise))
        return
    nom = load_mechanism(a.model)
    ps = parameters(nom, a.preset or next(iter(nom.presets)))
    lo, hi = (int(v) for v in a.seeds.split(":"))
    for seed in range(lo, hi):
        t0 = time.perf_counter()
        rec = draw(a, nom, ps, seed)
        print(json.dumps(rec | {"s": round(time.perf_counter() - t0, 1)}), flush=True)


if __name__ == "__main__":
    main()
