"""Benchmark of the core engine: pincal now, pincal 0.1 and the floors, in one run.

Run: python scripts/bench_core.py [--repeats 5] [--v01 /work/wt/v01] [--quick]
     python scripts/bench_core.py --quick --baseline /work/wt/base --label d307e66

Every operation is timed per pose (median of repeats) for

* pincal now (this checkout, batched paths),
* pincal 0.1 (the ``1d5694d`` commit checked out at ``--v01``; create it with
  ``git worktree add /work/wt/v01 1d5694d``), run in a subprocess with PYTHONPATH
  pointing there (skipped when the directory is missing); or any other checkout given
  as ``--baseline DIR`` with its ``--label`` (e.g. main before a change: ``git worktree
  add /work/wt/base REV``), which runs even with ``--quick``,
* the floors: a plain-numpy batched Newton/closed-form Stewart (same sizes: 6 legs,
  42 parameters) and, for the UR10, the Pinocchio calls alone
  (``framesForwardKinematics`` + ``computeFrameJacobian`` per pose), each timed in turns
  with its operation, repeat by repeat (the same machine conditions for both).

All processes run with one BLAS thread (``threadpool_limits(1)``; stated in the
output) and every time is CPU time of the process (``time.process_time``), which other
jobs on a shared machine disturb far less than wall-clock time; compare the ratios,
which are measured in the same run, rather than absolute times. Also printed:
the cost of one generic Stewart evaluation's parts (tree walk, closure residuals and
Jacobian) against the floor's whole evaluate + Jacobian, identify time and peak memory
for N = 1 000 … 10 000 poses (fresh subprocess each),
``pincal demo`` and the 4 096-candidate Stewart pose selection, and the cost of a joint
compliance term: identify geometric vs geometric+compliance at N = 1 000 (a UR5, and
the Stewart platform carrying a 20 kg payload; ``--compliance-only`` prints that table
alone).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pinocchio as pin
from threadpoolctl import threadpool_info, threadpool_limits

ROOT = Path(__file__).resolve().parents[1]
B_DEG = (-15, 15, 105, 135, 225, 255)
P_DEG = (-45, 45, 75, 165, 195, 285)
BASE = np.array([[0.3 * np.cos(t), 0.3 * np.sin(t), 0.0] for t in np.radians(B_DEG)])
PLAT = np.array([[0.15 * np.cos(t), 0.15 * np.sin(t), 0.0] for t in np.radians(P_DEG)])


def median_time(fn, repeats: int) -> float:
    """Median CPU time of ``fn()`` [s] (process time: robust on a shared machine)."""
    times = []
    for _ in range(repeats):
        t0 = time.process_time()
        fn()
        times.append(time.process_time() - t0)
    return statistics.median(times)


# ---------------------------------------------------------------------- floors
def _exp3(w: np.ndarray) -> np.ndarray:
    th = np.linalg.norm(w, axis=1)[:, None, None]
    K = np.zeros((w.shape[0], 3, 3))
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -w[:, 2], w[:, 1], -w[:, 0]
    K = K - np.swapaxes(K, 1, 2)
    t = np.maximum(th, 1e-12)
    return np.eye(3) + np.sin(t) / t * K + (1 - np.cos(t)) / t**2 * (K @ K)


def numpy_stewart_fk(L: np.ndarray, p: np.ndarray, R: np.ndarray, tol: float = 1e-12):
    """Batched closed-form Newton FK of the nominal Stewart (leg lengths L (N, 6))."""
    p, R = p.copy(), R.copy()
    for _ in range(50):
        a_w = PLAT @ np.swapaxes(R, 1, 2)  # (N, 6, 3)
        legs = a_w + p[:, None] - BASE
        norms = np.linalg.norm(legs, axis=2)
        r = norms - L
        if np.max(np.abs(r)) <= tol:
            return p, R, legs / norms[..., None], a_w
        n = legs / norms[..., None]
        J = np.concatenate([n, np.cross(a_w, n)], axis=2)
        dx = np.linalg.solve(J, -r[..., None])[..., 0]
        p = p + dx[:, :3]
        R = _exp3(dx[:, 3:]) @ R
    raise RuntimeError("numpy FK did not converge")


def numpy_stewart_jacobian(R, n, a_w):
    """(N, 6, 42) pose sensitivity to base/platform anchors and leg offsets (closed form)."""
    N = R.shape[0]
    Jx = np.concatenate([n, np.cross(a_w, n)], axis=2)  # d length / d(p, ω_world)
    dl = np.zeros((N, 6, 42))
    for i in range(6):
        dl[:, i, 3 * i : 3 * i + 3] = -n[:, i]
        dl[:, i, 18 + 3 * i : 21 + 3 * i] = (np.swapaxes(R, 1, 2) @ n[:, i, :, None])[..., 0]
        dl[:, i, 36 + i] = -1.0
    dX = -np.linalg.solve(Jx, dl)
    dX[:, 3:] = np.swapaxes(R, 1, 2) @ dX[:, 3:]  # rotation in the platform frame
    return dX


def paired_times(now: dict, floor: dict, repeats: int, n: int) -> tuple[dict, dict]:
    """Median CPU time per pose of each operation and of its floor, timed alternately.

    The shared machine's speed changes from minute to minute (the other core's load);
    timing an operation and its floor in turns, repeat by repeat, lets both see the
    same conditions, so their ratio is steadier than timing one block after the other.
    Each timed call follows an untimed call of the same operation (warm caches).
    """
    t_now: dict[str, list[float]] = {k: [] for k in now}
    t_floor: dict[str, list[float]] = {k: [] for k in floor}
    for _ in range(repeats):
        for key in floor:
            for fns, times in ((now, t_now), (floor, t_floor)):
                if key in fns:
                    fns[key]()  # untimed: caches warm for this operation, as in a block
                    t0 = time.process_time()
                    fns[key]()
                    times[key].append(time.process_time() - t0)
    return (
        {k: statistics.median(v) / n for k, v in t_now.items()},
        {k: statistics.median(v) / n for k, v in t_floor.items()},
    )


def floors(n: int) -> dict:
    import pincal

    rng = np.random.default_rng(0)
    mech = pincal.load_mechanism("stewart_6ups")
    rows = pincal.sample_actuators(mech, n, rng)
    T = [mech.forward(r) for r in rows]
    p_true = np.array([t.translation for t in T])
    R_true = np.array([t.rotation for t in T])
    L = np.linalg.norm(PLAT @ np.swapaxes(R_true, 1, 2) + p_true[:, None] - BASE, axis=2)
    T0 = mech.forward(mech.actuators_of(mech.q_home))
    p0, R0 = np.tile(T0.translation, (n, 1)), np.tile(T0.rotation, (n, 1, 1))
    pw, Rw = p_true + 1e-4, _exp3(np.full((n, 3), 1e-4)) @ R_true
    out = {}
    out["stewart FK cold"] = lambda: numpy_stewart_fk(L, p0, R0)

    def warm_eval():
        _, R, nn, a_w = numpy_stewart_fk(L, pw, Rw)
        numpy_stewart_jacobian(R, nn, a_w)

    out["stewart FK warm"] = lambda: numpy_stewart_fk(L, pw, Rw)
    out["stewart evaluate+J"] = warm_eval
    ur = pincal.load_mechanism("ur10")
    model, data = ur.model, ur.model.createData()
    fid = ur.frame_id(ur.measured_frame)
    qs = [ur.with_actuators(ur.q_home, r) for r in pincal.sample_actuators(ur, n, rng)]

    def ur_calls():
        for q in qs:
            pin.framesForwardKinematics(model, data, q)
            pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL)

    def ur_regressor():
        for q in qs:
            pin.framesForwardKinematics(model, data, q)
            pin.computeFrameKinematicRegressor(model, data, fid, pin.LOCAL)

    out["ur10 evaluate+J"] = ur_calls
    out["ur10 FK+regressor"] = ur_regressor
    return out


# ---------------------------------------------------------------------- worker
def worker(repeats: int, n: int, sizes: list[int]) -> dict:
    """Time the operations with whichever pincal is importable (now or 0.1)."""
    import pincal
    from pincal import sensitivity as sens_mod

    batched = hasattr(pincal.load_mechanism("wedge3"), "configurations_batch")
    if batched:
        try:
            from pincal.sensitivity.batch import sensitivities_batch
        except ImportError:  # a baseline checkout from before the sensitivity rooms
            from pincal.sensitivity._batch_jacobian import sensitivities_batch
    rng = np.random.default_rng(0)
    mech = pincal.load_mechanism("stewart_6ups")
    p42 = pincal.parameters(mech, "stewart42")
    rows = pincal.sample_actuators(mech, n, rng)
    qs = mech.configurations(rows)
    home = mech.q_home
    res: dict = {"version": pincal.__version__, "batched": batched}

    def fk_cold():
        if batched:
            mech.configurations_batch(rows)
        else:
            for r in rows:
                mech.configuration(r, home)

    def fk_warm():
        if batched:
            mech.configurations_batch(rows + 1e-4, qs)
        else:
            for r, q in zip(rows, qs, strict=True):
                mech.configuration(r + 1e-4, q)

    def evaluate(m, params, rr, qq):
        if batched:
            Q, bk = m.configurations_batch(rr + 1e-4, qq)
            sensitivities_batch(m, params, Q, bk)
        else:
            for r, q in zip(rr, qq, strict=True):
                sens_mod.pose_sensitivity(m, params, m.configuration(r + 1e-4, q))

    ops = {
        "stewart FK cold": fk_cold,
        "stewart FK warm": fk_warm,
        "stewart evaluate+J": lambda: evaluate(mech, p42, rows, qs),
    }
    ur = pincal.load_mechanism("ur10")
    full = pincal.parameters(ur, "full")
    ur_rows = pincal.sample_actuators(ur, n, rng)
    ur_qs = ur.configurations(ur_rows)
    ops["ur10 evaluate+J"] = lambda: evaluate(ur, full, ur_rows, ur_qs)
    for fn in ops.values():  # warm-up: first calls build caches
        fn()
    fl = floors(n)
    times, res["floor"] = paired_times(ops, fl, repeats, n)
    res.update(times)
    if batched:  # the parts of one generic evaluation, in turns with the floor's whole one
        Qs = mech.configurations(rows)
        bk = mech.batch_model.kinematics(Qs)
        parts = {
            "tree walk": lambda: mech.batch_model.kinematics(Qs),
            "closure terms": lambda: mech.closure_terms_batch(bk, columns=mech.free_dofs),
        }
        t_parts, t_floor = paired_times(
            parts, {k: fl["stewart evaluate+J"] for k in parts}, repeats, n
        )
        res["parts"] = {k: (t_parts[k], t_floor[k]) for k in parts}
    noise = pincal.NoiseModel(0.01, 0.02)
    true = np.random.default_rng(1).normal(0, 0.5e-3, len(p42))
    actual = p42.apply(mech, true)
    res["identify"] = {}
    for m in sizes:
        q_m = pincal.sample_actuators(mech, m, np.random.default_rng(m))
        meas = pincal.simulate_measurements(actual, q_m, noise, np.random.default_rng(m + 1))
        reps = max(3, repeats // 2)  # a single run can fall in a slow period of the machine
        t = median_time(lambda meas=meas: pincal.identify(mech, p42, meas), reps)
        r = pincal.identify(mech, p42, meas)
        res["identify"][m] = {
            "time": t,
            "iterations": r.iterations,
            "values": np.asarray(r.values).tolist(),
        }
    res["noise"] = _noise_estimate(pincal, mech, p42, actual, noise, repeats)
    return res


def _noise_estimate(pincal, mech, params, actual, noise, repeats: int) -> dict | None:
    """Identify 300 noisy poses with the noise declared and without (estimated)."""
    import dataclasses

    q_m = pincal.sample_actuators(mech, 300, np.random.default_rng(300))
    meas = pincal.simulate_measurements(actual, q_m, noise, np.random.default_rng(301))
    try:
        undeclared = dataclasses.replace(meas, noise=None)
    except TypeError:  # a version whose measurements carry no noise model
        return None
    reps = max(3, repeats // 2)
    out = {}
    for key, data in (("declared", meas), ("estimated", undeclared)):
        out[key] = median_time(lambda data=data: pincal.identify(mech, params, data), reps)
    w = pincal.identify(mech, params, undeclared).weighting
    out["fits"] = int(w.rounds)
    return out


def identify_memory(m: int) -> dict:
    """Identify with m poses in this (fresh) process: time and peak resident memory."""
    import pincal

    mech = pincal.load_mechanism("stewart_6ups")
    p42 = pincal.parameters(mech, "stewart42")
    actual = p42.apply(mech, np.random.default_rng(1).normal(0, 0.5e-3, len(p42)))
    q_m = pincal.sample_actuators(mech, m, np.random.default_rng(m))
    meas = pincal.simulate_measurements(
        actual, q_m, pincal.NoiseModel(0.01, 0.02), np.random.default_rng(m + 1)
    )
    base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    t0 = time.process_time()
    r = pincal.identify(mech, p42, meas)
    t = time.process_time() - t0
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return {"time": t, "iterations": r.iterations, "peak_mb": peak / 1024, "base_mb": base / 1024}


def design_and_demo() -> dict:
    import pincal
    from pincal.cli._demo_job import run_demo
    from pincal.design import DesignScaling, exchange, grid_candidates
    from pincal.workflow import DemoSettings

    mech = pincal.load_mechanism("stewart_6ups")
    params = pincal.parameters(mech, "stewart42")
    t0 = time.process_time()
    cands = grid_candidates(mech, params, 4, in_workspace=False)
    sc = DesignScaling(rows="noise", position_std=1e-5, orientation_std=1e-5)
    exchange(sc.apply(cands.jacobians, cands.components).J, 18, "O1", rng=1)
    t_sel = time.process_time() - t0
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.process_time()
        run_demo(DemoSettings(), Path(tmp) / "demo")
        t_demo = time.process_time() - t0
    return {"selection": t_sel, "candidates": int(cands.tried), "demo": t_demo}


# ---------------------------------------------------------------------- driver
def compliance_cost(repeats: int, n: int) -> dict:
    """Identify time, geometric vs geometric+compliance, on the same N compliant poses."""
    import dataclasses

    import pincal
    from pincal.model import Payload, actual_joint_values, with_joint_terms, with_payload

    stewart = pincal.load_mechanism("stewart_6ups")
    machines = (
        ("ur5, base", pincal.load_mechanism("ur5"), "base"),
        ("stewart42 + 20 kg", with_payload(stewart, Payload(20.0, (0.05, -0.02, 0.1))),
         "stewart42"),
    )  # fmt: skip
    out = {}
    for label, mech, preset in machines:
        geo = pincal.parameters(mech, preset)
        full = with_joint_terms(mech, geo, ["compliance"])
        rng = np.random.default_rng(7)
        truth = np.zeros(len(full))
        truth[: len(geo)] = rng.normal(0.0, 2e-4, len(geo))
        truth[full.joint_terms] = rng.normal(0.0, 1e-5, full.joint_terms.size)
        rows = pincal.sample_actuators(mech, n, rng)
        joints = actual_joint_values(mech, full, truth, rows)
        meas = pincal.simulate_measurements(full.apply(mech, truth), joints,
                                            pincal.NoiseModel(0.01, 0.01), rng)  # fmt: skip
        meas = dataclasses.replace(meas, q_act=rows)
        row = {}
        for key, params in (("geometric", geo), ("compliance", full)):
            its = pincal.identify(mech, params, meas).iterations  # also the warm-up

            def fit(m=mech, p=params, d=meas):
                return pincal.identify(m, p, d)

            row[key] = (median_time(fit, repeats), its, len(params))
        out[label] = row
    return out


def print_compliance(res: dict, repeats: int, n: int) -> None:
    print(f"\nidentify with a joint compliance term, N = {n} full poses (same compliant data; "
          f"CPU time, median of {repeats}, 1 BLAS thread):")  # fmt: skip
    print(f"  {'machine':20s} {'geometric':>20s} {'geometric+compliance':>24s} {'ratio':>7s}")
    for label, r in res.items():
        (tg, ig, ng), (tc, ic, nc) = r["geometric"], r["compliance"]
        print(f"  {label:20s} {tg:7.3f} s ({ng} p, {ig} it.) {tc:9.3f} s ({nc} p, {ic} it.) "
              f"{tc / tg:6.2f}×")  # fmt: skip


def _run(path: Path, args: list[str]) -> dict:
    env = dict(os.environ, PYTHONPATH=str(path), OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    out = subprocess.run(
        [sys.executable, str(Path(__file__).resolve()), *args],
        env=env,
        cwd=str(path),
        capture_output=True,
        text=True,
        check=False,
    )
    if out.returncode:
        raise RuntimeError(f"benchmark subprocess failed in {path}:\n{out.stderr[-3000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def _fmt(t: float | None) -> str:
    return "—" if t is None else f"{t * 1e6:.1f} µs"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--poses", type=int, default=1000, help="poses per timed batch")
    ap.add_argument("--v01", type=Path, default=Path("/work/wt/v01"))
    ap.add_argument("--baseline", type=Path, help="another checkout to compare (runs with --quick)")
    ap.add_argument("--label", default="0.1", help="the baseline's column label")
    ap.add_argument("--quick", action="store_true", help="skip N = 10 000 and the 0.1 run")
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--memory", type=int, default=0, help=argparse.SUPPRESS)
    ap.add_argument("--design", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--sizes", default="300,1000,3000", help="identify sizes")
    ap.add_argument("--compliance", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--compliance-only", action="store_true",
                    help="only the geometric vs geometric+compliance table")  # fmt: skip
    args = ap.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")]
    with threadpool_limits(1):
        if args.worker:
            print(json.dumps(worker(args.repeats, args.poses, sizes)))
            return
        if args.memory:
            print(json.dumps(identify_memory(args.memory)))
            return
        if args.design:
            print(json.dumps(design_and_demo()))
            return
        if args.compliance:
            print(json.dumps(compliance_cost(args.repeats, args.poses)))
            return
        blas = sorted({f"{i['internal_api']} {i['num_threads']}" for i in threadpool_info()})
    if args.compliance_only:
        cost = _run(ROOT, ["--compliance", f"--repeats={args.repeats}", f"--poses={args.poses}"])
        print_compliance(cost, args.repeats, args.poses)
        return
    now = _run(ROOT, ["--worker", f"--repeats={args.repeats}", f"--poses={args.poses}",
                      f"--sizes={args.sizes}"])  # fmt: skip
    old = None
    base = args.baseline if args.baseline is not None else args.v01
    if base.is_dir() and (args.baseline is not None or not args.quick):
        old = _run(base, ["--worker", f"--repeats={args.repeats}", f"--poses={args.poses}",
                              f"--sizes={args.sizes}"])  # fmt: skip
    libs = ", ".join(blas)
    print(f"pin {pin.__version__}, numpy {np.__version__}; BLAS threads in every process: 1 "
          f"(threadpool_limits(1), OPENBLAS_NUM_THREADS=1; libraries: {libs})")  # fmt: skip
    print(f"CPU time (time.process_time), median of {args.repeats} repeats over {args.poses} "
          f"random workspace poses; shared machine: compare the ratios (same run)\n")  # fmt: skip
    print("per pose; 'floor' = the floor timed in the same process, in turns with the operation")
    lab = args.label
    print(f"(repeat by repeat); the normalised {lab}/now ratio divides each version's time by its")
    print("own floor (load drift between the two processes)\n")
    head = f"{'operation':22s} {'now':>11s} {'floor':>10s} {'now/floor':>9s}"
    print(head + f" {lab:>11s} {'floor':>10s} {lab + '/now':>8s} {'normalised':>10s}")
    for key in ("stewart FK cold", "stewart FK warm", "stewart evaluate+J", "ur10 evaluate+J"):
        f_now = now["floor"][key]
        line = f"{key:22s} {_fmt(now[key]):>11s} {_fmt(f_now):>10s} {now[key] / f_now:8.1f}×"
        if old:
            f_old = old["floor"][key]
            norm = (old[key] / f_old) / (now[key] / f_now)
            line += (f" {_fmt(old[key]):>11s} {_fmt(f_old):>10s} {old[key] / now[key]:7.1f}×"
                     f" {norm:9.1f}×")  # fmt: skip
        print(line)
    print(f"{'ur10 FK + regressor':22s} {'':>11s} {_fmt(now['floor']['ur10 FK+regressor']):>10s}"
          f"  (pin.computeFrameKinematicRegressor, for reference)")  # fmt: skip
    if "parts" in now:
        print("\none generic Stewart evaluation (a warm solve makes three), in turns with the "
              "floor's whole evaluate + Jacobian:")  # fmt: skip
        for key, (t, f) in now["parts"].items():
            print(f"  {key:14s} {_fmt(t):>10s}   floor evaluate+J {_fmt(f):>10s}   {t / f:5.2f}×")
    print("\nidentify, Stewart 42 parameters (Gauss–Newton):")
    for m, r in now["identify"].items():
        line = f"  N = {int(m):5d}: now {r['time']:7.3f} s ({r['iterations']} it.)"
        if old:
            o = old["identify"][m]
            rel = np.max(np.abs(np.subtract(r["values"], o["values"]))) / np.max(
                np.abs(o["values"])
            )
            up = o["time"] / r["time"]
            line += (f"   {lab} {o['time']:7.3f} s ({o['iterations']} it.)   "
                     f"speed-up {up:5.1f}×   max rel. diff {rel:.1e}")  # fmt: skip
        print(line)
    if now.get("noise"):
        n = now["noise"]
        print(f"  N =   300, noise not declared (estimated by variance components): "
              f"{n['estimated']:.3f} s in {n['fits']} fits vs declared {n['declared']:.3f} s "
              f"({n['estimated'] / n['declared']:.2f}×)")  # fmt: skip
    print("\nidentify scaling (fresh process each; peak resident memory of the process):")
    big = [1000, 3000] + ([] if args.quick else [10000])
    for m in big:
        r = _run(ROOT, [f"--memory={m}"])
        print(f"  N = {m:5d}: {r['time']:7.3f} s = {1e3 * r['time'] / m:.3f} ms/pose "
              f"({r['iterations']} it.), peak RSS {r['peak_mb']:.0f} MB "
              f"(before identify {r['base_mb']:.0f} MB)")  # fmt: skip
    d = _run(ROOT, ["--design"])
    print(f"\nStewart pose selection, {d['candidates']} grid candidates (FK + Jacobians + "
          f"exchange O1, 18 poses): {d['selection']:.2f} s")  # fmt: skip
    print(f"pincal demo (run_demo, default settings): {d['demo']:.2f} s")
    cost = _run(ROOT, ["--compliance", f"--repeats={args.repeats}", f"--poses={args.poses}"])
    print_compliance(cost, args.repeats, args.poses)


if __name__ == "__main__":
    main()
