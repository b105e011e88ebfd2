"""Record every fit route's outputs, to compare two versions of the fit code.

Usage (one BLAS thread; run once on each version, from that version's root):
    python scripts/studies/fit_equivalence.py record OUT.pkl
    python scripts/studies/fit_equivalence.py compare BEFORE.pkl AFTER.pkl

Cases (36 fits): every bundled machine (stewart_6ups, hexaslide_6pus, pkm5, wedge3,
aacmm, ur5; default preset, 30 random poses, ±0.5 mm / 5 mrad errors) by Gauss–Newton
with declared and with estimated noise and by LM with Huber; on the Stewart also a
prior, a subset fit and the step-planned solver; joint fits (one pose file with and
without the 20 mm / 0.1 rad weak bound, UR5 socket plates with and without a known
distance by GN and LM, sockets + poses through ``identify``); UR5 marker fits (30 poses;
40 poses with a wrist that barely moves, so parameters are held) plain, with a prior,
with Huber and registration only. Recorded per fit: values, std, covariance, χ²/ν,
identified mask, message, success, iterations, cost history, residual statistics and
tables, weighting, the joint details (instrument values, gauge, weak, warnings, socket
centres) and the marker notes. ``compare`` prints every difference and the largest
relative difference per route.
"""

from __future__ import annotations

import os
import pickle
import sys

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np
import pinocchio as pin

from pincal.identification import (
    GaussNewtonOptions,
    IdentificationProblem,
    LMOptions,
    Prior,
    fit_markers,
    identify,
    identify_instruments,
    is_registration,
)
from pincal.measure import (
    KnownDistance,
    MarkerSetup,
    Measurements,
    SocketPlate,
    marker_mechanism,
    simulate_measurements,
    simulate_sockets,
)
from pincal.model import (
    BASE_JOINT,
    TOOL_JOINT,
    load_mechanism,
    parameters,
    sample_actuators,
    with_joint_origin,
)

NOISE = {"position": 0.01, "orientation": 0.1}  # mm, mrad


def _res(r) -> dict:
    joint = getattr(r, "joint", None)  # typed after the driver; annotations before
    notes = {**(joint.to_dict() if joint is not None else {}), **dict(r.annotations)}
    return {
        "values": np.array(r.full_values), "std": np.array(r.std),
        "cov": np.array(r.covariance), "chi2": r.reduced_chi2, "mask": np.array(r.identified),
        "msg": r.message, "ok": r.success, "it": r.iterations,
        "hist": np.array(r.cost_history, dtype=float), "before": repr(r.before),
        "after": repr(r.after), "ann": repr(notes), "resid": np.array(r.residuals),
        "w": None if r.weighting is None else repr(r.weighting),
    }  # fmt: skip


def _joint(j) -> dict:
    return {**_res(j.result), "x": j.values, "fitted": j.fitted, "jcov": j.covariance,
            "gauge": j.gauge, "weak": j.weak, "warn": j.warnings,
            "centres": dict(j.socket_centres)}  # fmt: skip


def _pose_cases(out: dict) -> None:
    for name in ["stewart_6ups", "hexaslide_6pus", "pkm5", "wedge3", "aacmm", "ur5"]:
        mech = load_mechanism(name)
        params = parameters(mech)
        rng = np.random.default_rng(1)
        bound = np.array([5e-4 if u == "m" else 5e-3 for u in params.units])
        actual = params.apply(mech, rng.uniform(-bound, bound))
        meas = simulate_measurements(actual, sample_actuators(mech, 30, rng), NOISE, rng)
        out[f"pose/{name}/gn-declared"] = _res(identify(mech, params, meas, noise=NOISE))
        out[f"pose/{name}/gn-estimated"] = _res(identify(mech, params, meas))
        out[f"pose/{name}/lm-huber"] = _res(
            identify(mech, params, meas, "lm", options=LMOptions(loss="huber"))
        )
        if name == "stewart_6ups":
            n = len(params)
            opts = GaussNewtonOptions(prior_std=(1e-3,) * n, prior_mean=(0.0,) * n)
            out[f"pose/{name}/gn-prior"] = _res(identify(mech, params, meas, options=opts,
                                                         noise=NOISE))  # fmt: skip
            sub = list(params.names[:20])
            out[f"pose/{name}/sub"] = _res(identify(mech, params, meas, fit=sub, noise=NOISE))
            out[f"pose/{name}/step"] = _res(identify(mech, params, meas, "step-planned",
                                                     noise=NOISE))  # fmt: skip
            for wb in [None, (0.02, 0.1)]:
                out[f"joint/{name}/pose/{wb}"] = _joint(
                    identify_instruments(mech, params, [meas], weak_bound=wb)
                )
        print(name, flush=True)


def _joint_cases(out: dict) -> None:
    ur5 = load_mechanism("ur5")
    params = parameters(ur5, "full")
    bound = np.array([1e-3 if u == "m" else 1e-2 for u in params.units])
    actual = params.apply(ur5, np.random.default_rng(2).uniform(-bound, bound))
    a = np.array([0.45, 0.10, 0.05])
    sockets = {"A": a, "B": a + np.array([0.05, 0, 0])}
    for known in [True, False]:
        plate = SocketPlate("plate", 5e-6, (KnownDistance("A", "B", 0.05, 2e-6),) if known else ())
        data = simulate_sockets(actual, plate, sockets, 30, np.random.default_rng(1))
        for method in ["gauss-newton", "lm"]:
            out[f"joint/sockets/{known}/{method}"] = _joint(
                identify_instruments(ur5, params, [data], method)
            )
        print("sockets", known, flush=True)
    rng = np.random.default_rng(3)
    sock = simulate_sockets(actual, SocketPlate("plate", 5e-6), sockets, 3, rng)
    pm = simulate_measurements(actual, sample_actuators(ur5, 20, rng), NOISE, rng)
    out["joint/mixed/identify"] = _res(identify(IdentificationProblem(ur5, params, [sock, pm])))


def _ur5_markers(n: int, wrist_span: float | None, seed: int):
    setup = MarkerSetup("wrist_3_link")
    mech = marker_mechanism("ur5", setup)
    frame = pin.SE3(pin.rpy.rpyToMatrix(0.2, 0.1, -0.5), np.array([0.8, 0.5, -0.2]))
    act = with_joint_origin(mech, BASE_JOINT, frame)
    act = with_joint_origin(act, TOOL_JOINT, pin.SE3(np.eye(3), np.array([0.02, 0.04, 0.1])))
    p = parameters(act, "chain")
    rng = np.random.default_rng(seed)
    x = rng.uniform(-1e-3, 1e-3, len(p))
    x[[is_registration(k) for k in p.names]] = 0.0
    act = p.apply(act, x)
    q = sample_actuators(mech, n, rng)
    if wrist_span is not None:
        q[:, 4:] = rng.uniform(-wrist_span, wrist_span, (n, 2))
    P = np.array([act.frame_placement(c).translation for c in act.configurations(q)])
    P += rng.normal(0, 5e-5, P.shape)
    return mech, setup, Measurements(q, P, None, ("x", "y", "z"), mech.measured_frame,
                                     mech.actuated)  # fmt: skip


def _marker_cases(out: dict) -> None:
    for n, span, seed in [(30, None, 1), (40, 0.02, 2)]:
        mech, setup, meas = _ur5_markers(n, span, seed)
        for kw in [{}, {"prior": Prior(1e-3, 1e-2)}, {"loss": "huber"},
                   {"registration_only": True}]:  # fmt: skip
            f = fit_markers(mech, setup, meas, **kw)
            extra = {"notes": f.notes, "method": f.method, "held": f.held_weak}
            out[f"marker/ur5/{n}/{span}/{kw}"] = {**_res(f.result), **extra}
        print("marker", n, flush=True)


def _compare(a: dict, b: dict) -> None:
    worst: dict[str, float] = {}
    for k, fits in a.items():
        if k not in b:
            print("MISSING", k)
            continue
        for f, va in fits.items():
            vb = b[k][f]
            if isinstance(va, (np.ndarray, float)):
                va, vb = np.asarray(va, float), np.asarray(vb, float)
                if va.shape != vb.shape:
                    print("SHAPE", k, f, va.shape, vb.shape)
                    continue
                if not va.size:
                    continue
                d = float(np.nanmax(np.abs(va - vb)) / max(np.nanmax(np.abs(va)), 1e-300))
                route = k.split("/")[0]
                worst[route] = max(worst.get(route, 0.0), d)
                if d > 0 or not np.array_equal(np.isnan(va), np.isnan(vb)):
                    print(f"{k} {f}: relative {d:.3g}")
            elif isinstance(va, dict):
                for c in va:
                    if not np.array_equal(va[c], vb[c]):
                        print(k, f, c, "differs")
            elif va != vb:
                print("DIFF", k, f, repr(va)[:200], "|", repr(vb)[:200])
    print(f"{len(a)} fits; largest relative difference per route: {worst}")


def main() -> None:
    if sys.argv[1:2] == ["record"] and len(sys.argv) == 3:
        out: dict = {}
        _pose_cases(out)
        _joint_cases(out)
        _marker_cases(out)
        with open(sys.argv[2], "wb") as fh:
            pickle.dump(out, fh)
        print(len(out), "fits recorded")
    elif sys.argv[1:2] == ["compare"] and len(sys.argv) == 4:
        with open(sys.argv[2], "rb") as fa, open(sys.argv[3], "rb") as fb:
            _compare(pickle.load(fa), pickle.load(fb))
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main()
