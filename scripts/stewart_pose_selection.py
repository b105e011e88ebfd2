"""Seed 000 study: measurement poses chosen on Jz vs the dimensionless Jzg (Stewart, 42 params).

Reproduces the simulation of seed 000 (its Figs. 4–7 and Table 6) on the bundled
6-UPS Stewart platform:

1. candidates: joint-space grid of ``--levels`` leg lengths per leg (4⁶ = 4096
   rows) pushed through the forward kinematics, kept inside the sidecar workspace;
2. m = 18 poses selected by add/remove exchange maximising an observability
   index computed on
   - Jz: the seed's unscaled Jacobian. The seed works in mm, so its Jz has
     position rows in mm/mm and orientation rows in rad/mm: in SI this is the
     Jacobian with orientation rows multiplied by 1 mm, i.e. Jzg with K = 1 mm;
   - Jzg: position rows divided by a characteristic length K (seed: K = 600 mm
     for their platform). Ours is chosen so that position and orientation rows
     have equal RMS over the candidates (``--K`` overrides);
3. three noise levels a decade apart; in each Monte-Carlo repetition an
   "actual" machine is drawn (42 errors, N(0, 0.5 mm)), the 18 poses are
   measured with noise, identified by Gauss–Newton (noise-whitened) and validated
   on 60 random workspace poses. The same draws are used for both designs and
   all noise levels (common random numbers), so the ratios are paired.

Table layout as the seed's Table 6: P = position error [mm] and θ = orientation
error [deg] (RMS over the 60 validation poses and the repetitions), S =
structural parameter error [mm] (RMS over the 42 parameters and repetitions);
"± x" is the Monte-Carlo standard error, "CRB" the Cramér–Rao prediction of the
same quantity, η = CRB MSE / achieved MSE (efficiency). Repeated for O2–O5.
Finally O1-optimised poses (noise-whitened scaling) vs 18 random poses at equal
noise.

Usage: python scripts/stewart_pose_selection.py [--reps 30] [--reps-other 12]
       [--levels 4] [--K 600] [--seed 0] [--indices O1 O2 O3 O4 O5]
"""

from __future__ import annotations

import argparse
import time
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

import pincal
from pincal.design import (
    DesignScaling,
    characteristic_length,
    cramer_rao_from_jacobian,
    efficiency,
    grid_candidates,
    select_poses,
)
from pincal.model import COMPONENTS

NOISE_LEVELS = (  # (position [mm], orientation [mrad])
    (0.1, 0.1),
    (0.01, 0.01),
    (0.001, 0.001),
)
ERROR_STD = 0.5e-3  # [m] std of the drawn geometric errors
M_POSES = 18
N_VALIDATION = 60


@dataclass
class Outcome:
    """Per-repetition results of one design at one noise level."""

    pos_ms: list[float]  # mean square validation position error [m²]
    rot_ms: list[float]  # mean square validation orientation error [rad²]
    param_err: list[np.ndarray]  # identified − true (n,)


def _poses(mech: pincal.Mechanism, q_rows: np.ndarray) -> list:
    qs = mech.configurations(q_rows)
    out = []
    for q in qs:
        out.append(mech.frame_placement(q))
    return out


def _validation_ms(calibrated: pincal.Mechanism, q_val: np.ndarray, actual_poses: list):
    pos, rot = [], []
    for Tm, Ta in zip(_poses(calibrated, q_val), actual_poses, strict=True):
        pos.append(np.sum((Tm.translation - Ta.translation) ** 2))
        rot.append(np.sum(pin.log3(Tm.rotation.T @ Ta.rotation) ** 2))
    return float(np.mean(pos)), float(np.mean(rot))


def _identify_errors(nominal, params, q_meas, actual, noise, rng_seed):
    meas = pincal.simulate_measurements(actual, q_meas, noise, np.random.default_rng(rng_seed))
    res = pincal.identify(nominal, params, meas, "gauss-newton")
    x = np.zeros(len(params))
    x[[params.index(n) for n in res.params.names]] = res.values
    return x, res.calibrated


def run_mc(nominal, params, designs: dict[str, np.ndarray], reps: int, seed: int, q_val):
    """Monte Carlo over repetitions; returns {(design, level): Outcome}."""
    out = {(d, lv): Outcome([], [], []) for d in designs for lv in range(len(NOISE_LEVELS))}
    rng = np.random.default_rng(seed)
    for r in range(reps):
        true = rng.normal(0.0, ERROR_STD, len(params))
        actual = params.apply(nominal, true)
        actual_val = _poses(actual, q_val)
        noise_seed = int(rng.integers(2**31))
        for name, q_meas in designs.items():
            if callable(q_meas):
                q_meas = q_meas(r)
            for lv, (sp, so) in enumerate(NOISE_LEVELS):
                noise = pincal.NoiseModel(sp, so)
                x, calibrated = _identify_errors(nominal, params, q_meas, actual, noise, noise_seed)
                pm, rm = _validation_ms(calibrated, q_val, actual_val)
                o = out[(name, lv)]
                o.pos_ms.append(pm)
                o.rot_ms.append(rm)
                o.param_err.append(x - true)
    return out


def _rms_se(samples: np.ndarray) -> tuple[float, float]:
    """RMS = sqrt(mean(samples)) of mean-square samples and its SE (delta method)."""
    s = np.asarray(samples, dtype=float)
    mean = float(np.mean(s))
    se = float(np.std(s, ddof=1) / np.sqrt(s.size)) if s.size > 1 else float("nan")
    rms = np.sqrt(mean)
    return rms, se / (2 * rms) if rms > 0 else float("nan")


def _ratio_se(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    """Ratio sqrt(mean a / mean b) of paired mean-square samples and its SE (delta method)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    ma, mb = a.mean(), b.mean()
    ratio_ms = ma / mb
    # var of ma/mb by the delta method with the paired covariance
    d = a / mb - ma * b / mb**2
    se_ms = float(np.std(d, ddof=1) / np.sqrt(a.size)) if a.size > 1 else float("nan")
    ratio = np.sqrt(ratio_ms)
    return float(ratio), se_ms / (2 * ratio)


def crb_for(design_J: np.ndarray, comps, level: int, Jv: np.ndarray, params):
    sp, so = NOISE_LEVELS[level]
    return cramer_rao_from_jacobian(
        design_J, comps, pincal.NoiseModel(sp, so), Jv, params.names, params.units
    )


def print_table(index, results, designs_J, comps, Jv, params, labels):
    deg = 180.0 / np.pi
    print(
        f"\n{index}: {'noise':>13} {'design':<18} {'P [mm]':>20} {'θ [deg]':>22} "
        f"{'S [mm]':>20} {'S CRB':>9} {'η':>12}"
    )
    for lv, (sp, so) in enumerate(NOISE_LEVELS):
        for key, label in labels.items():
            o = results[(key, lv)]
            P, Pse = _rms_se(o.pos_ms)
            T, Tse = _rms_se(o.rot_ms)
            err = np.array(o.param_err)
            S, Sse = _rms_se(np.mean(err**2, axis=1))
            crb = crb_for(designs_J[key], comps, lv, Jv, params)
            eff = efficiency(err, crb.covariance)
            print(
                f"    {sp:>5g}/{so:<5g}mm/mrad {label:<18} "
                f"{P * 1e3:9.5f} ± {Pse * 1e3:8.5f} {T * deg:10.6f} ± {Tse * deg:9.6f} "
                f"{S * 1e3:9.5f} ± {Sse * 1e3:8.5f} {crb.rms_std * 1e3:9.5f} "
                f"{eff.efficiency:5.2f} ± {eff.efficiency_se:4.2f}"
            )
    keys = list(labels)
    a, b = keys[0], keys[1]
    print(f"    ratios {labels[a]} / {labels[b]} (paired; > 1 means {labels[b]} is better):")
    for lv, (sp, so) in enumerate(NOISE_LEVELS):
        oa, ob = results[(a, lv)], results[(b, lv)]
        rp = _ratio_se(oa.pos_ms, ob.pos_ms)
        rt = _ratio_se(oa.rot_ms, ob.rot_ms)
        rs = _ratio_se(
            np.mean(np.array(oa.param_err) ** 2, 1), np.mean(np.array(ob.param_err) ** 2, 1)
        )
        ca = crb_for(designs_J[a], comps, lv, Jv, params)
        cb = crb_for(designs_J[b], comps, lv, Jv, params)
        print(
            f"    {sp:>5g}/{so:<5g}mm/mrad   P {rp[0]:.3f} ± {rp[1]:.3f}   "
            f"θ {rt[0]:.3f} ± {rt[1]:.3f}   S {rs[0]:.3f} ± {rs[1]:.3f}   (CRB: P "
            f"{ca.validation_position_rms / cb.validation_position_rms:.3f}, θ "
            f"{ca.validation_orientation_rms / cb.validation_orientation_rms:.3f}, S "
            f"{ca.rms_std / cb.rms_std:.3f})"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reps", type=int, default=30, help="MC repetitions for O1")
    parser.add_argument("--reps-other", type=int, default=12, help="MC repetitions for O2–O5")
    parser.add_argument("--levels", type=int, default=4, help="grid levels per leg")
    parser.add_argument("--K", type=float, default=None, help="characteristic length [mm]")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--restarts", type=int, default=3, help="exchange random starts")
    parser.add_argument("--indices", nargs="+", default=["O1", "O2", "O3", "O4", "O5"])
    parser.add_argument("--no-random", action="store_true", help="skip O1 vs random poses")
    args = parser.parse_args()
    t_start = time.perf_counter()

    nominal = pincal.load_mechanism("stewart_6ups")
    params = pincal.parameters(nominal, "stewart42")
    cands = grid_candidates(nominal, params, args.levels)
    comps = cands.components
    print(
        f"Stewart 6-UPS, {len(params)} parameters (stewart42); {cands.summary()}; "
        f"m = {M_POSES}; errors N(0, {ERROR_STD * 1e3} mm); GN identification; "
        f"{N_VALIDATION} validation poses"
    )
    K_bal = characteristic_length(cands.jacobians, comps)
    K = args.K * 1e-3 if args.K is not None else K_bal
    print(
        f"K: balanced RMS(position rows)/RMS(orientation rows) over the candidates = "
        f"{K_bal * 1e3:.1f} mm; used K = {K * 1e3:.1f} mm (seed: 600 mm for its platform)"
    )
    scalings = {
        "Jz": DesignScaling(rows="K", K=1e-3),
        "Jzg": DesignScaling(rows="K", K=K),
    }
    labels = {"Jz": "Jz (K = 1 mm)", "Jzg": f"Jzg (K = {K * 1e3:.0f} mm)"}
    for name, sc in scalings.items():
        print(f"  {name}: {sc.describe()}")
    rng_val = np.random.default_rng(args.seed + 1000)
    q_val = pincal.sample_actuators(nominal, N_VALIDATION, rng_val)
    Jv = pincal.identification_jacobian(nominal, params, q_val, components=COMPONENTS).reshape(
        N_VALIDATION, 6, len(params)
    )

    for index in args.indices:
        reps = args.reps if index == "O1" else args.reps_other
        designs, designs_J = {}, {}
        for name, sc in scalings.items():
            d = select_poses(cands, M_POSES, index, sc, rng=args.seed, restarts=args.restarts)
            designs[name] = d.q_act
            designs_J[name] = d.candidates.jacobians
            h = d.selection.history
            print(
                f"{index} on {name}: {h[0]:.5g} → {h[-1]:.5g} in {d.selection.iterations} "
                f"exchanges; cond(J unscaled SI) = "
                f"{np.linalg.cond(d.candidates.jacobians.reshape(-1, len(params))):.3g}"
            )
        t0 = time.perf_counter()
        res = run_mc(nominal, params, designs, reps, args.seed, q_val)
        print(f"  Monte Carlo: {reps} repetitions × 3 noise levels × 2 designs "
              f"({time.perf_counter() - t0:.0f} s)")  # fmt: skip
        print_table(
            index, res, designs_J, comps, Jv, params, {"Jz": labels["Jz"], "Jzg": labels["Jzg"]}
        )

    if not args.no_random:
        sp, so = NOISE_LEVELS[1]
        sc = DesignScaling(rows="noise", position_std=sp * 1e-3, orientation_std=so * 1e-3)
        d = select_poses(cands, M_POSES, "O1", sc, rng=args.seed, restarts=args.restarts)
        rng_rand = np.random.default_rng(args.seed + 7)
        random_sets = [
            pincal.sample_actuators(nominal, M_POSES, rng_rand) for _ in range(args.reps)
        ]
        designs = {"O1": d.q_act, "random": lambda r: random_sets[r]}
        res = run_mc(nominal, params, designs, args.reps, args.seed + 1, q_val)
        a = np.mean(np.array(res[("random", 1)].param_err) ** 2, axis=1)
        b = np.mean(np.array(res[("O1", 1)].param_err) ** 2, axis=1)
        ratio, se = _ratio_se(a, b)
        mean_abs_r = float(np.mean(np.abs(res[("random", 1)].param_err)))
        mean_abs_o = float(np.mean(np.abs(res[("O1", 1)].param_err)))
        print(
            f"\nO1-optimised ({sc.describe()}) vs random 18 poses at noise {sp} mm / {so} mrad, "
            f"{args.reps} repetitions (new random set each):\n"
            f"  mean |parameter error|: random {mean_abs_r * 1e3:.5f} mm, O1 {mean_abs_o * 1e3:.5f}"
            f" mm (ratio {mean_abs_r / mean_abs_o:.2f});  "
            f"RMS ratio random/O1 = {ratio:.2f} ± {se:.2f}"
        )
    print(f"\ntotal time {time.perf_counter() - t_start:.0f} s")


if __name__ == "__main__":
    main()
