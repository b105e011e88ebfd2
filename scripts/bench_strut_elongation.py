"""Benchmark: the exact strut elongation against the first-order fixed point it replaced.

Per sag, on the hexaslide of scripts/studies/hexaslide_deflection.py (20 kg payload,
geometric errors N(0, 0.2 mm / 0.2 mrad), ``--poses`` random poses, seed 5), the CPU time
of pincal's deflection (``actual_joint_values``: per pose the fixed point δL = c·F of the
machine with its struts lengthened) and, in turns in the same run, of the first-order
fixed point ``q = u + L(q)·c`` on the term's columns (pincal's deflection before
289c85b). Median of ``--repeats``, one BLAS thread, ``time.process_time``.

    PYTHONPATH=. python scripts/bench_strut_elongation.py [--poses 60] [--repeats 3]
"""

from __future__ import annotations

import argparse
import importlib.util
import statistics
import sys
import time
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from pincal.model import actual_joint_values, joint_term_basis

HERE = Path(__file__).resolve().parent


def _hexa():
    path = HERE / "studies" / "hexaslide_deflection.py"
    spec = importlib.util.spec_from_file_location("hexaslide_deflection", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules["hexaslide_deflection"] = module  # its dataclasses look their module up
    spec.loader.exec_module(module)
    return module


def _first_order(actual, sub, c, rows) -> int:
    """Iterate ``q = u + L(q)·c`` to 1e-13 m; the number of iterations."""
    q = rows.copy()
    for n in range(1, 61):
        new = rows + joint_term_basis(actual, sub, q, {}) @ c
        step, q = float(np.max(np.abs(new - q))), new
        if step < 1e-13:
            return n
    return 60


def _cpu(fn, *args) -> float:
    """CPU seconds of ``fn(*args)``."""
    t0 = time.process_time()
    fn(*args)
    return time.process_time() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sags", default="0.01,0.1,0.5", help="strut sags [mm], comma list")
    ap.add_argument("--poses", type=int, default=60)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    hexa = _hexa()
    mech = hexa.with_payload(hexa.load_mechanism(hexa.HEXASLIDE), hexa.PAYLOAD)
    params = hexa.with_joint_terms(mech, hexa.parameters(mech, "pus54"), ("strut-compliance",))
    comp = np.asarray(params.joint_terms)
    print(f"hexaslide + 20 kg, {args.poses} poses; CPU seconds, median of {args.repeats}, "
          "one BLAS thread")  # fmt: skip
    print("| sag | exact | per pose | first order | iterations | exact / first order |")
    print("|---|---|---|---|---|---|")
    for sag in (1e-3 * float(s) for s in args.sags.split(",")):
        rng = np.random.default_rng(5)
        truth = np.zeros(len(params))
        truth[:54] = rng.normal(0.0, 2e-4, 54)
        truth[comp] = -sag / 66.8 * rng.uniform(0.5, 1.5, comp.size)  # [m/N]
        rows = hexa.sample_actuators(mech, args.poses, rng)
        actual, sub = params.apply(mech, truth), params.subset(comp)
        exact, first = [], []
        for _ in range(args.repeats):
            exact.append(_cpu(actual_joint_values, mech, params, truth, rows))
            first.append(_cpu(_first_order, actual, sub, truth[comp], rows))
        n = _first_order(actual, sub, truth[comp], rows)
        e, f = statistics.median(exact), statistics.median(first)
        print(f"| {sag * 1e3:g} mm | {e:.2f} s | {e / args.poses * 1e3:.0f} ms | {f:.2f} s "
              f"| {n} | {e / f:.2f}× |", flush=True)  # fmt: skip


if __name__ == "__main__":
    with threadpool_limits(1):
        main()
