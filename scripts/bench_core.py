"""Benchmark of the core engine on the 6-UPS Stewart platform.

Run: python scripts/bench_core.py [--repeats 7]

Prints a table of median times over repeats (each repeat loops over a batch of
poses): generic FK (cold / warm start), IK, the analytic identification Jacobian per
pose, finite-difference Jacobians for comparison, a plain-numpy Stewart Newton FK
measured in the same run, and full 42-parameter identifications.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
import pinocchio as pin

import pincal

B_DEG = (-15, 15, 105, 135, 225, 255)
P_DEG = (-45, 45, 75, 165, 195, 285)
BASE = np.array([[0.3 * np.cos(t), 0.3 * np.sin(t), 0.0] for t in np.radians(B_DEG)])
PLAT = np.array([[0.15 * np.cos(t), 0.15 * np.sin(t), 0.0] for t in np.radians(P_DEG)])


def numpy_stewart_fk(lengths: np.ndarray, p0: np.ndarray, R0: np.ndarray, tol=1e-12):
    """Plain-numpy Newton FK of the nominal Stewart platform (pose as p, R)."""
    p, R = p0.copy(), R0.copy()
    for _ in range(50):
        a_w = PLAT @ R.T
        legs = a_w + p - BASE
        norms = np.linalg.norm(legs, axis=1)
        r = norms - lengths
        if np.max(np.abs(r)) <= tol:
            return p, R
        n = legs / norms[:, None]
        J = np.hstack([n, np.cross(a_w, n)])  # d length / d(p, world rotation)
        dx = np.linalg.solve(J, -r)
        p = p + dx[:3]
        R = pin.exp3(dx[3:]) @ R
    raise RuntimeError("numpy FK did not converge")


def median_time(fn, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    mech = pincal.load_mechanism("stewart_6ups")
    p42 = pincal.parameters(mech, "stewart42")
    full = pincal.parameters(mech, "full")
    rows = pincal.sample_actuators(mech, 50, rng)
    targets = [mech.forward(r) for r in rows]
    qs = mech.configurations(rows)
    n = len(rows)
    home = mech.q_home
    T_home = mech.forward(mech.actuators_of(home))

    def fk_cold():
        for r in rows:
            mech.configuration(r, home)

    def fk_warm():  # guess = solution of a pose 0.1 mm / 0.1 mrad away along the path
        for r, q in zip(rows, qs, strict=True):
            mech.configuration(r + 1e-4, q)

    def ik():
        for T in targets:
            mech.inverse(T)

    def jac42():
        for q in qs:
            pincal.sensitivity.pose_sensitivity(mech, p42, q)

    def jacfull():
        for q in qs:
            pincal.sensitivity.pose_sensitivity(mech, full, q)

    def np_fk():
        for r in rows:
            numpy_stewart_fk(r, T_home.translation, T_home.rotation)

    sub = rows[:2]

    def fd42_rebuild():  # central FD by re-solving the loops of rebuilt models
        for k in range(len(p42)):
            e = np.zeros(len(p42))
            e[k] = 1e-6
            for sign in (1, -1):
                m = p42.apply(mech, sign * e)
                for r in sub:
                    m.forward(r)

    res = {}
    res["FK cold (from home)"] = median_time(fk_cold, args.repeats) / n
    res["FK warm (nearby solution)"] = median_time(fk_warm, args.repeats) / n
    res["numpy Stewart Newton FK (cold)"] = median_time(np_fk, args.repeats) / n
    res["IK (from home)"] = median_time(ik, args.repeats) / n
    res["Jacobian, 42 parameters"] = median_time(jac42, args.repeats) / n
    res["Jacobian, full (204)"] = median_time(jacfull, args.repeats) / n
    res["central FD, 42 params (rebuild + FK)"] = median_time(fd42_rebuild, 1) / len(sub)
    fd_lower = 2 * len(p42) * res["FK warm (nearby solution)"]

    print(f"pincal {pincal.__version__}, pin {pin.__version__}, numpy {np.__version__}")
    print(f"median of {args.repeats} repeats over {n} random workspace poses\n")
    print(f"{'operation':44s} {'time per pose':>14s}")
    for name, t in res.items():
        print(f"{name:44s} {t * 1e6:11.1f} µs")
    print(f"{'FD lower bound: 2·42 warm FK solves':44s} {fd_lower * 1e6:11.1f} µs")
    print()
    jac = res["Jacobian, 42 parameters"]
    fk_ratio = res["FK cold (from home)"] / res["numpy Stewart Newton FK (cold)"]
    print(f"{'generic FK cold / numpy FK':44s} {fk_ratio:9.2f} ×")
    ratio_fd = res["central FD, 42 params (rebuild + FK)"] / jac
    print(f"{'analytic Jacobian speed-up vs FD (rebuild)':44s} {ratio_fd:9.0f} ×")
    print(f"{'analytic Jacobian speed-up vs FD lower bound':44s} {fd_lower / jac:9.0f} ×")

    noise = pincal.NoiseModel(0.01, 0.02)
    true = rng.normal(0, 0.5e-3, len(p42))
    actual = p42.apply(mech, true)
    print()
    for m in (30, 300):
        q_m = pincal.sample_actuators(mech, m, rng)
        meas = pincal.simulate_measurements(actual, q_m, noise, rng)
        reps = max(1, args.repeats // 3)
        t = median_time(lambda meas=meas: pincal.identify(mech, p42, meas), reps)
        r = pincal.identify(mech, p42, meas)
        print(f"identify 42 parameters, {m:3d} poses (GN, {r.iterations} it.)  {t:8.3f} s")


if __name__ == "__main__":
    main()
