"""Study: pincal's strut elongation against an independent one, and the first-order
substitute its Jacobian columns use.

The truth is scripts/studies/hexaslide_deflection.py's statics: carriages at the command,
struts lengthened by the fixed point ``ℓ' = ℓ + c·F(ℓ')`` of the true machine. pincal's
deflection (``actual_joint_values``) solves the same fixed point on its own machine; its
columns (``joint_term_basis``) are first order: a rigid substitute (nominal strut
lengths, carriages moved by ``q = u + E(q)·c·F(q)``) with the forces ``F`` taken there.
Per sag, on the hexaslide with 20 kg, geometric errors N(0, 0.2 mm / 0.2 mrad),
``--poses`` random poses (seed 5, as tests/studies/test_deflection_truths.py):

* pincal: distance of pincal's deflected platform from the exact one, RMS / max [µm];
* substitute: the same for the first-order fixed point of the columns [µm];
* force error: the substitute's strut forces against the elongated machine's at the
  exact pose, largest relative error, and the elongation ``c·ΔF`` it makes [µm];
* midpoint: the substitute with the joint change's tangent ``E`` taken at the midpoint
  of command and deflected joints (``q = u + E((u+q)/2)·c·F(q)``), to tell a path
  (integration) error from the substitute's geometry.

    PYTHONPATH=. python scripts/studies/strut_model_error.py
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
from pathlib import Path

import numpy as np

from pincal.model import actual_joint_values, sample_actuators, strut_loads

HERE = Path(__file__).resolve().parent


def _hexa():
    spec = importlib.util.spec_from_file_location(
        "hexaslide_deflection", HERE / "hexaslide_deflection.py"
    )
    module = importlib.util.module_from_spec(spec)
    sys.modules["hexaslide_deflection"] = module  # its dataclasses look their module up
    spec.loader.exec_module(module)
    return module


def _substitute(actual, names, c, rows, midpoint: bool) -> np.ndarray:
    """Joint values (m, 6) of ``q = u + E(q)·c·F(q)``, or with ``E((u+q)/2)`` [m]."""
    q = rows.copy()
    for _ in range(60):
        F, E = strut_loads(actual, q, names)
        if midpoint:
            E = strut_loads(actual, 0.5 * (rows + q), names)[1]
        new = rows + np.einsum("mj,mja->ma", F * c, E)
        step, q = float(np.max(np.abs(new - q))), new
        if step < 1e-13:
            break
    return q


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sags", default="0.01,0.1,0.5,1", help="strut sags s [mm], comma list")
    ap.add_argument("--poses", type=int, default=6)
    args = ap.parse_args()
    hexa = _hexa()
    print("sag [mm] | pincal RMS/max [µm] | substitute RMS/max [µm] | force error (rel.) "
          "| its elongation [µm] | midpoint RMS/max [µm]")  # fmt: skip
    for sag in (1e-3 * float(s) for s in args.sags.split(",")):
        mech = hexa.with_payload(hexa.load_mechanism(hexa.HEXASLIDE), hexa.PAYLOAD)
        params = hexa.with_joint_terms(mech, hexa.parameters(mech, "pus54"), ("strut-compliance",))
        comp = np.asarray(params.joint_terms)
        rng = np.random.default_rng(5)
        truth = np.zeros(len(params))
        truth[:54] = rng.normal(0.0, 2e-4, 54)
        truth[comp] = -sag / 66.8 * rng.uniform(0.5, 1.5, comp.size)  # [m/N]
        rows = sample_actuators(mech, args.poses, rng)
        actual = params.apply(mech, truth)
        h = hexa.Hexaslide.of(actual)
        names, c = tuple(params.parameters[k].joint for k in comp), truth[comp]
        exact = [h.deflected(u, c, *hexa.HOME) for u in rows]
        rel, elong = [], []
        tangent = _substitute(actual, names, c, rows, midpoint=False)
        for u, qm, (t, R) in zip(rows, tangent, exact, strict=True):
            F_exact = h.forces(u, t, R)
            F_model = strut_loads(actual, qm[None], names)[0][0]
            rel.append(np.max(np.abs(F_model - F_exact)) / np.max(np.abs(F_exact)))
            elong.append(np.max(np.abs(c * (F_model - F_exact))) * 1e6)
        errs = []
        pincal = actual_joint_values(mech, params, truth, rows)
        for joints in (pincal, tangent, _substitute(actual, names, c, rows, midpoint=True)):
            d = [np.linalg.norm(actual.forward(q).translation - t) * 1e6
                 for q, (t, _) in zip(joints, exact, strict=True)]  # fmt: skip
            errs.append(f"{np.sqrt(np.mean(np.square(d))):.3g} / {max(d):.3g}")
        print(f"{sag * 1e3:g} | {errs[0]} | {errs[1]} | {max(rel):.2g} | {max(elong):.3g} "
              f"| {errs[2]}", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
