"""Ball-in-socket calibration with and without the plate's known distance (held out).

Usage:
    python scripts/studies/socket_plate.py [--model ur5] [--poses 30] [--std 0.005]
        [--seed 1]

The "actual" arm is MODEL (``full`` preset) with uniform errors ±1 mm / ±10 mrad
(seed 2). Its flange ball is seated ``--poses`` times in each of two sockets 50 mm
apart (the flange tilted up to 0.6 rad from pointing down, seating noise ``--std`` mm
per axis); the plate's known distance (50 mm, 1σ 2 µm) is given or withheld. Held
out: 10 new poses in socket A and 10 in a socket C, 250 mm from A, never in a fit; the
distance between the mean predicted ball centres of A and C (and of A and B, 10 new
poses each) is compared with the truth. Without the known distance nothing measured
fixes the length scale: the fit holds it at nominal and says so (``warnings``).
"""

from __future__ import annotations

import argparse

import numpy as np

from pincal.identification import identify_instruments
from pincal.measure import KnownDistance, SocketPlate, simulate_sockets
from pincal.model import load_mechanism, parameters


def held_out_errors(mech, actual, std: float, sockets: dict, rng) -> dict[str, float]:
    """|predicted − true| distance [mm] of socket pairs A–B and A–C at new poses."""
    held = simulate_sockets(actual, SocketPlate("held", std), sockets, 10, rng)
    P = np.array([mech.frame_placement(q).translation for q in mech.configurations(held.q_act)])
    names = np.array(held.socket)
    c = {s: P[names == s].mean(axis=0) for s in held.sockets}
    true = {s: np.linalg.norm(sockets["A"] - sockets[s]) for s in ("B", "C")}
    return {f"A–{s}": 1e3 * abs(np.linalg.norm(c["A"] - c[s]) - true[s]) for s in ("B", "C")}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", default="ur5")
    ap.add_argument("--poses", type=int, default=30, help="poses per socket in the fit")
    ap.add_argument("--std", type=float, default=0.005, help="seating 1σ per axis [mm]")
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    mech = load_mechanism(a.model)
    params = parameters(mech, "full")
    bound = np.array([1e-3 if u == "m" else 1e-2 for u in params.units])
    actual = params.apply(mech, np.random.default_rng(2).uniform(-bound, bound))
    p = mech.frame_placement(mech.q_home).translation
    A = np.array([0.6 * p[0], 0.6 * p[1], p[2]])
    across = np.array([-p[1], p[0], 0.0]) / np.hypot(p[0], p[1])
    sockets = {"A": A, "B": A + 0.05 * across, "C": A + 0.25 * across}
    std = a.std * 1e-3
    print(f"{a.model}: {a.poses} poses per socket, seating σ {a.std} mm, errors ±1 mm/±10 mrad")
    print(f"{'known distance':>15s} {'warning':>8s} {'held-out A–B':>13s} {'A–C (250 mm)':>13s}")
    rng = np.random.default_rng(a.seed)
    base = held_out_errors(mech, actual, std, sockets, np.random.default_rng(99))
    print(f"{'(nominal)':>15s} {'':>8s} {base['A–B']:10.4f} mm {base['A–C']:10.4f} mm")
    for known in (True, False):
        plate = SocketPlate("plate", std, (KnownDistance("A", "B", 0.05, 2e-6),) if known else ())
        fit_sockets = {k: sockets[k] for k in "AB"}
        data = simulate_sockets(actual, plate, fit_sockets, a.poses, rng)
        out = identify_instruments(mech, params, [data])
        err = held_out_errors(out.result.calibrated_mechanism, actual, std, sockets,
                              np.random.default_rng(99))  # fmt: skip
        print(f"{'yes' if known else 'no':>15s} {'yes' if out.warnings else 'no':>8s} "
              f"{err['A–B']:10.4f} mm {err['A–C']:10.4f} mm")  # fmt: skip
        for w in out.warnings:
            print(f"  warning: {w}")


if __name__ == "__main__":
    main()
