"""Study: how well the data tell the constants an instrument file declares (1σ per set-up).

Usage:
    python scripts/studies/declared_constants.py [--seeds 0:4] [--poses 60]

Per set-up and seed: an actual machine drawn as ``scripts/studies/instrument_gate.py``
draws it (errors uniform in ±1 mm / ±10 mrad on the model's first preset, or the preset
named), random workspace poses, the kind's typical set-up read with σ = 0.01 mm, the joint
fit, and the 1σ of each declared constant (bar length scale, sphere radius, gain) from
the fit's whitened Jacobian, ``1/‖(I − Π_J) c‖`` — what the gauge compares with 1e-3 of
the constant's value. Set-ups: the typical ones (ballbar pivot, sphere centre 0.1 m below
the tool points' centre), the sphere 30 mm below instead, and the Stewart platform with
only its six leg offsets fitted.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from pincal.identification import default_instrument, identify_instruments
from pincal.measure import simulate_instrument
from pincal.model import load_mechanism, sample_actuators
from pincal.sensitivity import parameters

STD = 1e-5  # m
RRR3 = str(Path(__file__).resolve().parents[2] / "tests/model/machines/rrr3/rrr3.urdf")
#: (name, model, preset or "legs", kind, sphere centre depth below the tool points [m])
SETUPS = (
    ("Stewart, sphere (typical)", "stewart_6ups", None, "sphere", 0.1),
    ("Stewart (6 leg offsets), sphere", "stewart_6ups", "legs", "sphere", 0.1),
    ("Stewart, sphere 30 mm below", "stewart_6ups", None, "sphere", 0.03),
    ("Stewart, ballbar", "stewart_6ups", None, "distance", 0.1),
    ("3-RRR, ballbar", RRR3, "base", "distance", 0.1),
)


def constant_stds(model: str, preset: str | None, kind: str, below: float, seed: int,
                  poses: int) -> dict[str, tuple[float, str]]:  # fmt: skip
    """Declared constant name → (its 1σ [its unit], its unit) for one seeded campaign."""
    mech = load_mechanism(model)
    params = parameters(mech, next(iter(mech.presets)) if preset in (None, "legs") else preset)
    if preset == "legs":
        params = parameters(mech, [n for n in params.names if n.endswith("_slide.offset")])
    rng = np.random.default_rng(seed)
    bound = np.array([1e-3 if u == "m" else 1e-2 for u in params.units])
    actual = params.apply(mech, rng.uniform(-bound, bound))
    q = sample_actuators(mech, poses, rng)
    inst, theta, ids = default_instrument(mech, kind, q, std=STD)
    if kind == "sphere":  # the study's own set-up choice, not the library's
        theta = theta + np.array([0.0, 0.0, 0.1 - below])
    data = simulate_instrument(actual, inst, theta, q, rng, ids=ids)
    fit = identify_instruments(mech, params, [data])
    assert fit.whitened is not None
    A, z = fit.whitened
    J = A.reshape(len(z), -1)
    x = fit.values[len(params) :]
    P = _tool_points(mech, params, fit.values, q)
    out = {}
    for c in inst.declared_constants(P, x, ids):
        col = np.asarray(c.derivative) / inst.std
        left = col - J @ np.linalg.lstsq(J, col, rcond=None)[0]
        out[c.name] = (1.0 / float(np.linalg.norm(left)), c.unit)
    return out


def _tool_points(mech, params, values, q) -> np.ndarray:
    """Tool points [m] of the fitted machine at the actuator rows q."""
    fitted = params.apply(mech, values[: len(params)])
    return np.array([fitted.frame_placement(c).translation for c in fitted.configurations(q)])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", default="0:4", help="first:last+1")
    ap.add_argument("--poses", type=int, default=60)
    a = ap.parse_args(argv)
    lo, hi = (int(v) for v in a.seeds.split(":"))
    print(f"# 1σ of the declared constants, {a.poses} random poses, σ {STD * 1e3} mm, "
          f"seeds {lo}..{hi - 1}")  # fmt: skip
    for name, model, preset, kind, below in SETUPS:
        per: dict[str, list[tuple[float, str]]] = {}
        for seed in range(lo, hi):
            for k, su in constant_stds(model, preset, kind, below, seed, a.poses).items():
                per.setdefault(k, []).append(su)
        for k, v in per.items():
            vals = ", ".join(f"{s * 1e6:.1f} µm" if u == "m" else f"{s * 1e3:.2f} ‰" for s, u in v)
            print(f"{name:34s} {k:18s} 1σ: {vals}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
