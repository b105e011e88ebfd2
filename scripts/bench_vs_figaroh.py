"""pincal vs figaroh on the same simulated UR10 calibration problem.

Usage:
    pip install figaroh          # the optional [bench] extra
    python scripts/bench_vs_figaroh.py [--seed 0] [--noise 0.01] [--sizes 50 200 1000]

Problem (scripts/studies/ur10_calibration.py): example-robot-data UR10, a position target
80 mm off the tool0 flange, unknown base (instrument) frame and target offset,
joint-origin errors 0.1–1 mm / 0.5–2 mrad and joint offsets 0.5–2 mrad; N = 50, 200
and 1000 random configurations (``--sizes``), position noise σ per coordinate;
validation on 200 fresh configurations. Both tools get the same configurations and
the same noisy points.

pincal: ``pincal.identification._identify`` (Gauss–Newton, analytic Jacobian) on the ``chain``
preset, reduced to its identifiable base set. figaroh: its structural base-parameter
selection (``calculate_base_kinematics_regressor``, ``full_params``, unknown base and
tip frames) and its forward model ``calc_updated_fkm``, solved with
``scipy.optimize.least_squares(method="lm")`` as its ``BaseCalibration`` does; its
config-file/CSV layer is bypassed by filling the ``calib_config`` dict directly.
figaroh's base parameters are linear combinations in its own convention, so its
parameter error is not comparable and is not reported; the validation error is.

Times are wall seconds of the identification alone (model loading excluded for both),
the median of ``--repeats`` runs; BLAS runs single-threaded for both tools
(threadpoolctl), as pincal's small dense solves are fastest that way on a shared
machine. The last column is figaroh's time over pincal's at the same N.

If figaroh is not installed or fails, the script says why and exits with status 0.
"""

from __future__ import annotations

import argparse
import importlib.util
import logging
import statistics
import sys
import time
import traceback
from pathlib import Path

import numpy as np
import pinocchio as pin

import pincal

HERE = Path(__file__).resolve().parent


def _load_study():
    path = HERE / "studies" / "ur10_calibration.py"
    spec = importlib.util.spec_from_file_location("ur10_calibration", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules["ur10_calibration"] = module
    spec.loader.exec_module(module)
    return module


def _rms_max(x: np.ndarray) -> tuple[float, float]:
    return float(np.sqrt(np.mean(x**2))), float(np.max(np.abs(x)))


def _median_time(run, repeats: int):
    """Median wall seconds of ``repeats`` calls of ``run()`` and the last result."""
    times, result = [], None
    for _ in range(max(1, repeats)):
        t0 = time.perf_counter()
        result = run()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), result


def run_pincal(study, problem, meas, repeats: int = 1) -> dict:
    seconds, result = _median_time(
        lambda: pincal.identify(problem.nominal, problem.params, meas), repeats
    )
    idx = [problem.params.index(n) for n in result.params.names]
    err = result.values - problem.truth[idx]
    is_len = np.array([u == "m" for u in result.params.units])
    val = pincal.pose_errors(result.calibrated, problem.actual, problem.q_validation).position
    return {
        "seconds": seconds,
        "n_params": len(result.params),
        "param_len": _rms_max(err[is_len]),
        "param_ang": _rms_max(err[~is_len]),
        "validation": _rms_max(val),
    }


def figaroh_config(model, n_samples: int) -> dict:
    """figaroh's calib_config for UR10 tool0 position, unknown base and tip frames."""
    from figaroh.calibration.config import get_sup_joints

    act = get_sup_joints(model, "universe", "tool0")
    fid = model.getFrameId("tool0")
    return {
        "robot_name": model.name,
        "q0": pin.neutral(model),
        "instance": {},
        "NbMarkers": 1,
        "measurability": [True, True, True, False, False, False],
        "calibration_index": 3,
        "start_frame": "universe",
        "end_frame": "tool0",
        "free_flyer": False,
        "IDX_TOOL": fid,
        "tool_joint": model.frames[fid].parentJoint,
        "actJoint_idx": act,
        "config_idx": [model.joints[i].idx_q for i in act],
        "NbJoint": len(act),
        "base_pose": None,
        "tip_pose": None,
        "calib_model": "full_params",
        "param_name": [],
        "non_geom": False,
        "eps": 1e-3,
        "PLOT": 0,
        "coeff_regularize": 0.0,
        "outlier_eps": 0.05,
        "random_seed": 0,
        "estimation": {},
        "known_baseframe": False,
        "known_tipframe": False,
        "base_to_ref_frame": None,
        "ref_frame": None,
        "NbSample": n_samples,
    }


def run_figaroh(problem, meas, repeats: int = 1) -> dict:
    import scipy.optimize
    from figaroh.calibration import calibration_tools as ct
    from figaroh.calibration.parameter import add_base_name, add_pee_name

    from pincal.model import example_robot_urdf

    model = pin.buildModelFromUrdf(str(example_robot_urdf("ur10")))
    data = model.createData()
    q = np.asarray(meas.q_act)  # UR10: 6 revolute joints, q order = actuated order
    if model.nq != q.shape[1]:
        raise RuntimeError(f"figaroh UR10 model has nq={model.nq}, expected {q.shape[1]}")
    n = len(q)
    measured = meas.positions.T.ravel()  # component-major, as figaroh's PEE

    def solve():
        cfg = figaroh_config(model, n)
        ct.calculate_base_kinematics_regressor(q, model, data, cfg, tol_qr=1e-6)
        add_base_name(cfg)
        add_pee_name(cfg)

        def residual(var):
            return ct.calc_updated_fkm(model, data, var, q, cfg) - measured

        x0 = np.zeros(len(cfg["param_name"]))
        return cfg, scipy.optimize.least_squares(residual, x0, method="lm")

    seconds, (cfg, sol) = _median_time(solve, repeats)
    qv = problem.q_validation
    cfg_v = dict(cfg, NbSample=len(qv))
    predicted = ct.calc_updated_fkm(model, data, sol.x, qv, cfg_v).reshape(3, -1).T
    actual = np.array([problem.actual.forward(row).translation for row in qv])
    val = np.linalg.norm(predicted - actual, axis=1)
    return {
        "seconds": seconds,
        "n_params": len(cfg["param_name"]),
        "param_len": (float("nan"), float("nan")),
        "param_ang": (float("nan"), float("nan")),
        "validation": _rms_max(val),
        "success": bool(sol.success),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--noise", type=float, default=0.01, help="position noise σ [mm]")
    parser.add_argument("--sizes", type=int, nargs="+", default=[50, 200, 1000])
    parser.add_argument("--repeats", type=int, default=3, help="timed runs per tool and N")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.WARNING)
    try:
        import figaroh
        import figaroh.calibration.calibration_tools  # noqa: F401

        figaroh_error = None
    except Exception as exc:  # ImportError, or a broken install
        figaroh_error = f"figaroh cannot be imported: {type(exc).__name__}: {exc}"
    study = _load_study()
    rows = []
    from threadpoolctl import threadpool_limits

    blas = threadpool_limits(limits=1, user_api="blas")
    for n in args.sizes:
        problem = study.make_problem("ur10", n, "position", seed=args.seed)
        meas = pincal.simulate_measurements(
            problem.actual,
            problem.q_rows,
            {"position": args.noise},
            np.random.default_rng(args.seed + 100),
        )
        rows.append(("pincal", n, run_pincal(study, problem, meas, args.repeats)))
        if figaroh_error is None:
            try:
                rows.append(("figaroh", n, run_figaroh(problem, meas, args.repeats)))
            except Exception as exc:
                figaroh_error = (
                    f"figaroh failed on this problem: {type(exc).__name__}: {exc}\n"
                    + traceback.format_exc(limit=3)
                )
    blas.restore_original_limits()
    print(
        f"UR10, position target 80 mm off tool0, unknown base + tool frames, "
        f"noise σ = {args.noise} mm per coordinate, validation on 200 fresh configurations; "
        f"median of {args.repeats} runs, BLAS 1 thread"
    )
    print(
        "| tool | N | time [s] | identified | param err RMS/max [µm] | "
        "param err RMS/max [µrad] | validation RMS/max [mm] | figaroh / pincal |"
    )
    print("|---|---|---|---|---|---|---|---|")
    pincal_time = {n: r["seconds"] for tool, n, r in rows if tool == "pincal"}
    for tool, n, r in rows:
        pl, pa, v = r["param_len"], r["param_ang"], r["validation"]
        ptxt = "n/a" if np.isnan(pl[0]) else f"{pl[0] * 1e6:.2f} / {pl[1] * 1e6:.2f}"
        atxt = "n/a" if np.isnan(pa[0]) else f"{pa[0] * 1e6:.2f} / {pa[1] * 1e6:.2f}"
        print(
            f"| {tool} | {n} | {r['seconds']:.3f} | {r['n_params']} | {ptxt} | {atxt} | "
            f"{v[0] * 1e3:.4f} / {v[1] * 1e3:.4f} | "
            + (f"{r['seconds'] / pincal_time[n]:.1f}× |" if tool == "figaroh" else "|")
        )
    if figaroh_error is not None:
        print(f"\nfigaroh not compared: {figaroh_error}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
