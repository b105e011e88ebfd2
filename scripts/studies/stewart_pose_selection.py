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
   on 60 random workspace poses.

Random numbers: every index (and the O1-vs-random comparison) has its own seed
stream, ``SeedSequence([seed, index number])``, so no two rows of the summary share
draws; inside one index both designs see the same drawn machine and the same noise
stream (paired), and each noise level gets its own independent noise draw.

Table layout as the seed's Table 6: P = position error [mm] and θ = orientation
error [deg] (RMS over the 60 validation poses and the repetitions), S =
structural parameter error [mm] (RMS over the 42 parameters and repetitions);
"± x" is the Monte-Carlo standard error, "CRB" the Cramér–Rao prediction of the
same quantity, η = whitened efficiency n / mean (x̂ − x)ᵀF(x̂ − x) (unit-free, 1 for
an efficient estimator). The problem is linear at these error sizes, so every error
scales with the noise: the summary pools the three levels after dividing each
mean square by its σ², and prints the ratios Jz ÷ Jzg beside the ratios of the
Cramér–Rao predictions (the exact expectation of the Monte-Carlo ratio in that
linear regime). Finally O1-optimised poses (noise-whitened scaling) vs 18 random
poses at equal noise.

Usage: python scripts/studies/stewart_pose_selection.py [--reps 100] [--reps-random 30]
       [--levels 4] [--K 600] [--seed 0] [--indices O1 O2 O3 O4 O5] [--jobs 2]
"""

from __future__ import annotations

import argparse
import time
from dataclasses import dataclass, field

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
from pincal.executor import Executor
from pincal.model import COMPONENTS

MODEL, PRESET = "stewart_6ups", "stewart42"
NOISE_LEVELS = (  # (position [mm], orientation [mrad])
    (0.1, 0.1),
    (0.01, 0.01),
    (0.001, 0.001),
)
ERROR_STD = 0.5e-3  # [m] std of the drawn geometric errors
M_POSES = 18
N_VALIDATION = 60
STREAM_RANDOM = 6  # seed-stream number of the O1-vs-random comparison (indices use 1..5)


@dataclass
class Outcome:
    """Per-repetition results of one design at one noise level."""

    pos_ms: list[float] = field(default_factory=list)  # validation position MS [m²]
    rot_ms: list[float] = field(default_factory=list)  # validation orientation MS [rad²]
    param_err: list[np.ndarray] = field(default_factory=list)  # identified − true (n,)


def _model() -> tuple[pincal.Mechanism, pincal.ParameterSet]:
    """Nominal mechanism and parameters (10 ms; loaded per repetition, as Mechanism
    objects do not pickle to joblib workers)."""
    nominal = pincal.load_mechanism(MODEL)
    return nominal, pincal.parameters(nominal, PRESET)


def stream(seed: int, index: str) -> np.random.SeedSequence:
    """The independent seed stream of one index ("O1".."O5") or "random"."""
    number = STREAM_RANDOM if index == "random" else int(index[1:])
    return np.random.SeedSequence([seed, number])


def _poses(mech: pincal.Mechanism, q_rows: np.ndarray) -> list:
    return [mech.frame_placement(q) for q in mech.configurations(q_rows)]


def _validation_ms(calibrated: pincal.Mechanism, q_val: np.ndarray, actual_poses: list):
    pos, rot = [], []
    for Tm, Ta in zip(_poses(calibrated, q_val), actual_poses, strict=True):
        pos.append(np.sum((Tm.translation - Ta.translation) ** 2))
        rot.append(np.sum(pin.log3(Tm.rotation.T @ Ta.rotation) ** 2))
    return float(np.mean(pos)), float(np.mean(rot))


def _one_repetition(designs, r: int, seq: np.random.SeedSequence, levels, q_val):
    """One drawn machine measured with every design at every level: {(d, lv): (P, θ, err)}."""
    nominal, params = _model()
    rng = np.random.default_rng(seq)
    true = rng.normal(0.0, ERROR_STD, len(params))
    noise_seeds = rng.integers(2**31, size=len(NOISE_LEVELS))  # independent per level
    actual = params.apply(nominal, true)
    actual_val = _poses(actual, q_val) if q_val is not None else None
    out = {}
    for name, q in designs.items():
        q_meas = q[r] if q.ndim == 3 else q
        for lv in levels:
            noise = pincal.NoiseModel(*NOISE_LEVELS[lv])
            meas = pincal.simulate_measurements(
                actual, q_meas, noise, np.random.default_rng(int(noise_seeds[lv]))
            )
            res = pincal.identify(nominal, params, meas, "gauss-newton")
            x = np.zeros(len(params))
            x[[params.index(n) for n in res.params.names]] = res.values
            pm = rm = float("nan")
            if actual_val is not None:
                pm, rm = _validation_ms(res.calibrated, q_val, actual_val)
            out[(name, lv)] = (pm, rm, x - true)
    return out


def _repetition(args: tuple):
    """One Monte-Carlo repetition as an executor item (``args`` of :func:`_one_repetition`)."""
    return _one_repetition(*args)


def run_mc(
    designs: dict[str, np.ndarray],
    reps: int,
    seq: np.random.SeedSequence,
    q_val: np.ndarray | None,
    levels=(0, 1, 2),
    n_jobs: int = 1,
    scheduler: str | None = None,
) -> dict[tuple[str, int], Outcome]:
    """Monte Carlo on the bundled Stewart model; returns {(design, level): Outcome}.

    Args:
        designs: name → actuator rows (m, 6), or (reps, m, 6) for a new set per repetition.
        reps: repetitions; repetition r uses the r-th child of ``seq``.
        q_val: validation poses (m_v, 6), or None to skip the validation errors.
        levels: indices into NOISE_LEVELS.
        n_jobs: local processes without a scheduler (1: run here).
        scheduler: a Dask scheduler (``local:N`` or ``tcp://host:port``), or None:
            :class:`pincal.executor.Executor`. Each repetition carries its own seed, so
            the result does not depend on the backend or the worker count.
    """
    children = seq.spawn(reps)
    args = [(designs, r, children[r], tuple(levels), q_val) for r in range(reps)]
    with Executor(scheduler, n_jobs) as ex:
        if scheduler is not None and __name__ != "__main__":  # imported (a test): the
            ex.client().upload_file(__file__)  # workers import the script as its module
        parts = ex.map(_repetition, args, progress="Monte Carlo").values()
    out = {(d, lv): Outcome() for d in designs for lv in levels}
    for part in parts:
        for key, (pm, rm, err) in part.items():
            out[key].pos_ms.append(pm)
            out[key].rot_ms.append(rm)
            out[key].param_err.append(err)
    return out


def _rms_se(samples) -> tuple[float, float]:
    """RMS = sqrt(mean(samples)) of mean-square samples and its SE (delta method)."""
    s = np.asarray(samples, dtype=float)
    mean = float(np.mean(s))
    se = float(np.std(s, ddof=1) / np.sqrt(s.size)) if s.size > 1 else float("nan")
    rms = np.sqrt(mean)
    return rms, se / (2 * rms) if rms > 0 else float("nan")


def ratio_se(a, b) -> tuple[float, float]:
    """Ratio sqrt(mean a / mean b) of paired mean-square samples and its SE (delta method)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    ma, mb = a.mean(), b.mean()
    d = a / mb - ma * b / mb**2  # influence function of ma/mb, paired covariance included
    se_ms = float(np.std(d, ddof=1) / np.sqrt(a.size)) if a.size > 1 else float("nan")
    ratio = np.sqrt(ma / mb)
    return float(ratio), se_ms / (2 * ratio)


def crb_for(design_J: np.ndarray, comps, level: int, Jv, params):
    """Cramér–Rao report of a design at one noise level."""
    return cramer_rao_from_jacobian(
        design_J, comps, pincal.NoiseModel(*NOISE_LEVELS[level]), Jv, params.names, params.units
    )


def pooled(results, key: str, quantity: str, levels) -> np.ndarray:
    """Mean squares of one design over all levels, each divided by its σ² (linear regime)."""
    out = []
    for lv in levels:
        o = results[(key, lv)]
        s2 = (NOISE_LEVELS[lv][0] * 1e-3) ** 2
        if quantity == "P":
            out.append(np.asarray(o.pos_ms) / s2)
        elif quantity == "θ":
            out.append(np.asarray(o.rot_ms) / s2)
        else:
            out.append(np.mean(np.array(o.param_err) ** 2, axis=1) / s2)
    return np.concatenate(out)


def bound_ratios(designs_J, comps, Jv, params, a="Jz", b="Jzg") -> dict[str, float]:
    """Cramér–Rao ratios a ÷ b of P, θ and S (noise-level independent)."""
    ca, cb = (crb_for(designs_J[k], comps, 1, Jv, params) for k in (a, b))
    return {
        "P": ca.validation_position_rms / cb.validation_position_rms,
        "θ": ca.validation_orientation_rms / cb.validation_orientation_rms,
        "S": ca.rms_std / cb.rms_std,
    }


def mc_ratios(results, levels, a="Jz", b="Jzg") -> dict[str, tuple[float, float]]:
    """Monte-Carlo ratios a ÷ b of P, θ, S pooled over ``levels``, with standard errors."""
    return {
        q: ratio_se(pooled(results, a, q, levels), pooled(results, b, q, levels))
        for q in ("P", "θ", "S")
    }


def print_table(index, results, designs_J, comps, Jv, params, labels):
    deg = 180.0 / np.pi
    print(
        f"\n{index}: {'noise':>13} {'design':<18} {'P [mm]':>20} {'θ [deg]':>22} "
        f"{'S [mm]':>20} {'S CRB':>9} {'η whitened':>12}"
    )
    for lv, (sp, so) in enumerate(NOISE_LEVELS):
        for key, label in labels.items():
            o = results[(key, lv)]
            P, Pse = _rms_se(o.pos_ms)
            T, Tse = _rms_se(o.rot_ms)
            err = np.array(o.param_err)
            S, Sse = _rms_se(np.mean(err**2, axis=1))
            crb = crb_for(designs_J[key], comps, lv, Jv, params)
            eff = efficiency(err, crb.covariance, params.units)
            print(
                f"    {sp:>5g}/{so:<5g}mm/mrad {label:<18} "
                f"{P * 1e3:9.5f} ± {Pse * 1e3:8.5f} {T * deg:10.6f} ± {Tse * deg:9.6f} "
                f"{S * 1e3:9.5f} ± {Sse * 1e3:8.5f} {crb.rms_std * 1e3:9.5f} "
                f"{eff.whitened:5.2f} ± {eff.whitened_se:4.2f}"
            )
    a, b = list(labels)[:2]
    print(f"    ratios {labels[a]} / {labels[b]} (paired; > 1 means {labels[b]} is better):")
    for lv, (sp, so) in enumerate(NOISE_LEVELS):
        r = mc_ratios(results, [lv], a, b)
        print(
            f"    {sp:>5g}/{so:<5g}mm/mrad   "
            + "   ".join(f"{q} {v:.3f} ± {se:.3f}" for q, (v, se) in r.items())
        )
    r = mc_ratios(results, range(len(NOISE_LEVELS)), a, b)
    c = bound_ratios(designs_J, comps, Jv, params, a, b)
    print(
        "    pooled over the levels  "
        + "   ".join(f"{q} {v:.3f} ± {se:.3f}" for q, (v, se) in r.items())
        + "   (CRB: "
        + ", ".join(f"{q} {v:.3f}" for q, v in c.items())
        + ")"
    )
    return r, c


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reps", type=int, default=100, help="MC repetitions per index")
    parser.add_argument("--reps-random", type=int, default=30, help="O1 vs random repetitions")
    parser.add_argument("--levels", type=int, default=4, help="grid levels per leg")
    parser.add_argument("--K", type=float, default=None, help="characteristic length [mm]")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--restarts", type=int, default=3, help="exchange random starts")
    parser.add_argument("--indices", nargs="+", default=["O1", "O2", "O3", "O4", "O5"])
    parser.add_argument("--no-random", action="store_true", help="skip O1 vs random poses")
    parser.add_argument("--jobs", type=int, default=1, help="local processes for the MC")
    parser.add_argument(
        "--scheduler",
        default=None,
        metavar="local:N|tcp://HOST:PORT",
        help="run the MC on dask.distributed (pip install 'pincal[dask]')",
    )
    args = parser.parse_args()
    t_start = time.perf_counter()

    nominal, params = _model()
    cands = grid_candidates(nominal, params, args.levels)
    comps = cands.components
    print(
        f"Stewart 6-UPS, {len(params)} parameters ({PRESET}); {cands.summary()}; "
        f"m = {M_POSES}; errors N(0, {ERROR_STD * 1e3} mm); GN identification; "
        f"{N_VALIDATION} validation poses; {args.reps} repetitions per index, seed {args.seed}"
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

    summary = {}
    for index in args.indices:
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
        res = run_mc(
            designs, args.reps, stream(args.seed, index), q_val, n_jobs=args.jobs,
            scheduler=args.scheduler,
        )  # fmt: skip
        print(f"  Monte Carlo: {args.reps} repetitions × 3 noise levels × 2 designs "
              f"({time.perf_counter() - t0:.0f} s)")  # fmt: skip
        summary[index] = print_table(index, res, designs_J, comps, Jv, params, labels)

    print(
        f"\nSummary: ratios Jz ÷ Jzg (> 1: Jzg better), Monte Carlo pooled over the three "
        f"levels ({3 * args.reps} paired samples per index, ± standard error) vs Cramér–Rao"
    )
    print("| index | P | θ | S | P (CRB) | θ (CRB) | S (CRB) |")
    print("|---|---|---|---|---|---|---|")
    for index, (r, c) in summary.items():
        print(
            f"| {index} | "
            + " | ".join(f"{v:.3f} ± {se:.3f}" for v, se in r.values())
            + " | "
            + " | ".join(f"{v:.3f}" for v in c.values())
            + " |"
        )

    if not args.no_random:
        sp, so = NOISE_LEVELS[1]
        sc = DesignScaling(rows="noise", position_std=sp * 1e-3, orientation_std=so * 1e-3)
        d = select_poses(cands, M_POSES, "O1", sc, rng=args.seed, restarts=args.restarts)
        rng_rand = np.random.default_rng(args.seed + 7)
        random_sets = np.array(
            [pincal.sample_actuators(nominal, M_POSES, rng_rand) for _ in range(args.reps_random)]
        )
        designs = {"O1": d.q_act, "random": random_sets}
        res = run_mc(designs, args.reps_random, stream(args.seed, "random"), None, (1,), args.jobs,
                     args.scheduler)  # fmt: skip
        a = np.mean(np.array(res[("random", 1)].param_err) ** 2, axis=1)
        b = np.mean(np.array(res[("O1", 1)].param_err) ** 2, axis=1)
        ratio, se = ratio_se(a, b)
        mean_abs_r = float(np.mean(np.abs(res[("random", 1)].param_err)))
        mean_abs_o = float(np.mean(np.abs(res[("O1", 1)].param_err)))
        print(
            f"\nO1-optimised ({sc.describe()}) vs random 18 poses at noise {sp} mm / {so} mrad, "
            f"{args.reps_random} repetitions (new random set each):\n"
            f"  mean |parameter error|: random {mean_abs_r * 1e3:.5f} mm, O1 {mean_abs_o * 1e3:.5f}"
            f" mm (ratio {mean_abs_r / mean_abs_o:.2f});  "
            f"RMS ratio random/O1 = {ratio:.2f} ± {se:.2f}"
        )
    print(f"\ntotal time {time.perf_counter() - t_start:.0f} s")


if __name__ == "__main__":
    main()
