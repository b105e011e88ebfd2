"""What a ballbar-only or probe-only campaign identifies, against a full-pose tracker.

For the Stewart (stewart42) and the hexaslide (pus54), three campaigns of the same
number of poses:

* tracker — full pose (σ = 10 µm, 0.05 mrad) at random workspace poses;
* ballbar — bar length (σ = 1 µm) at poses on the sphere of bar length around the
  pivot, selected by exchange (O1) from 300 candidates;
* probe — deflection on a reference sphere (σ = 1 µm), likewise.

Per campaign: the rank of the joint machine + instrument Jacobian, how many machine
parameters enter the base set, what the instrument cannot see (in words), the
Cramér–Rao median std of the fitted machine parameters, and Monte-Carlo evidence that
the joint Gauss–Newton fit attains the bound: mean Mahalanobis distance
``d²/k = δᵀ C⁻¹ δ / k`` of the fitted set (≈ 1) with its standard error.

Run: ``PYTHONPATH=. python scripts/studies/instrument_campaigns.py --reps 20``. The Monte
Carlo runs at the stated noise σ and at σ/10 (the small-noise limit of the bound).
"""

from __future__ import annotations

import argparse
import dataclasses
import re
import time

import numpy as np

from pincal.design import select_poses
from pincal.identification import (
    InstrumentProblem,
    identify_instruments,
    instrument_candidates,
    instrument_identifiability,
)
from pincal.measure import (
    Distance,
    NoiseModel,
    Sphere,
    simulate_instrument,
    simulate_measurements,
)
from pincal.model import load_mechanism, parameters, sample_actuators
from pincal.sensitivity import analyse_jacobian

MACHINES = (("stewart_6ups", "stewart42"), ("hexaslide_6pus", "pus54"))


def _select(mech, params, inst, theta, m, seed):
    cands = instrument_candidates(mech, params, inst, theta, 300, rng=seed, max_tilt=0.15)
    J = cands.jacobians[:, 0, :]
    n = len(params)
    order = np.r_[np.arange(n, J.shape[1]), np.arange(n)]
    ident = analyse_jacobian(J[:, order], tuple(cands.param_names[i] for i in order))
    base = np.sort(order[ident.base])
    sub = dataclasses.replace(
        cands,
        jacobians=cands.jacobians[:, :, base],
        param_names=tuple(cands.param_names[i] for i in base),
    )
    return cands.q_act[select_poses(sub, m, "O1", rng=seed).indices]


def campaign(mech, params, kind, m, seed, scale=1.0):
    """(datasets factory, instrument set-up or None) of one campaign of m poses, with
    the noise scaled by ``scale``."""
    home = mech.frame_placement(mech.q_home).translation
    if kind == "tracker":
        rows = sample_actuators(mech, m, np.random.default_rng(seed))
        noise = NoiseModel(0.01 * scale, 0.05 * scale)

        def make(actual, rng):
            return [simulate_measurements(actual, rows, noise, rng)]

        return make, None
    if kind == "ballbar":
        inst, theta = Distance(1e-6 * scale), np.r_[home - [0.0, 0.0, 0.1], 0.0]
    else:
        inst, theta = Sphere(1e-6 * scale, radius=0.05), home - [0.0, 0.0, 0.02]
    rows = _select(mech, params, inst, theta, m, seed)

    def make(actual, rng):
        return [simulate_instrument(actual, inst, theta, rows, rng)]

    return make, (inst, theta)


def study(model, preset, m, reps, scales=(1.0, 0.1), seed=0):
    mech = load_mechanism(model)
    params = parameters(mech, preset)
    n = len(params)
    out = []
    for kind in ("tracker", "ballbar", "probe"):
        t0 = time.time()
        make, setup = campaign(mech, params, kind, m, seed)
        prob = InstrumentProblem(mech, params, make(mech, np.random.default_rng(1)))
        ident = prob.analyse()
        order = np.r_[np.arange(n, len(prob.names)), np.arange(n)]
        base = np.sort(order[ident.base])
        base_m = base[base < n]
        truth = np.zeros(len(prob.names))
        truth[base_m] = np.random.default_rng(seed + 5).uniform(-5e-4, 5e-4, base_m.size)
        actual = params.apply(mech, truth[:n])
        mc = {}
        for scale in scales:
            make_s, _ = campaign(mech, params, kind, m, seed, scale) if scale != 1 else (make, 0)
            d2 = []
            cov = None
            for r in range(reps):
                data = make_s(actual, np.random.default_rng(1000 + r))
                fit = identify_instruments(mech, params, data)
                if cov is None:
                    p_true = InstrumentProblem(mech, params, data)
                    x_true = truth[:n] if setup is None else np.r_[truth[:n], setup[1]]
                    _, J, _ = p_true.evaluate(x_true)
                    cov = np.linalg.inv(J[:, fit.fitted].T @ J[:, fit.fitted])
                    if scale == 1:
                        std_m = np.sqrt(np.diag(cov))[fit.fitted < n]
                delta = (fit.values - x_true)[fit.fitted]
                d2.append(float(delta @ np.linalg.solve(cov, delta)) / delta.size)
            d2 = np.array(d2)
            mc[scale] = (float(d2.mean()), float(d2.std(ddof=1) / np.sqrt(reps)))
        unseen = "; ".join(
            w.replace(" of every tool point", "") for w in _words(mech, params, setup)
        )
        out.append(
            dict(
                machine=model, campaign=kind, poses=m, equations=prob.n_equations,
                rank=ident.rank, unknowns=len(prob.names), machine_base=base_m.size, n=n,
                crb_median_um=float(np.median(std_m) * 1e6),
                mc=mc,
                unseen=unseen, seconds=time.time() - t0,
            )
        )  # fmt: skip
        print(out[-1], flush=True)
    return out


def _words(mech, params, setup):
    """Compact words for what the campaign's instrument cannot identify."""
    if setup is None:
        return []
    rep = instrument_identifiability(mech, params, setup[0], theta=setup[1])
    short = [re.sub(r" about the axe?s .* through", " about", w) for w in rep.invisible]
    words = [f"{w} (unseen)" for w in short] + [f"{w} (absorbed)" for w in rep.absorbed]
    return [*words, f"{rep.n_still} tool rotation(s) about the tool point (unseen)"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--poses", type=int, default=60)
    ap.add_argument("--reps", type=int, default=30)
    args = ap.parse_args()
    rows = []
    for model, preset in MACHINES:
        rows += study(model, preset, args.poses, args.reps)
    print()
    print(
        "| machine | campaign | poses | equations | joint rank / unknowns | machine base / n "
        "| CRB median σ [µm] | mean d²/k ± SE at σ | … at σ/10 | not identified |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(
            f"| {r['machine']} | {r['campaign']} | {r['poses']} | {r['equations']} | "
            f"{r['rank']} / {r['unknowns']} | {r['machine_base']} / {r['n']} | "
            f"{r['crb_median_um']:.3g} | "
            + " | ".join(f"{a:.3f} ± {b:.3f}" for a, b in r["mc"].values())
            + " | "
            + f"{r['unseen'] or '-'} |"
        )


if __name__ == "__main__":
    main()
