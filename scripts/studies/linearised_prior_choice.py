"""Can a first-order leave-fold-out replace the refits that choose a marker prior?

Run: python scripts/studies/linearised_prior_choice.py [--markers 1 2 3] [--seed 0]

``prior: auto`` cross-validates every candidate σ of the grid by refitting K folds: on the
shipped TIAGo session that is most of ``pincal run``'s time (issue 34). The cheap
alternative is the one-step leave-fold-out of the fit on all poses: with the weighted
Jacobian J, residuals r (measured − model, whitened), robust weights W and the prior's
precision P at the solution, the fold F's residuals predicted without it are
``r_F + J_F δ``, ``δ = (N − J_Fᵀ W_F J_F)⁻¹ J_Fᵀ W_F r_F``, ``N = Jᵀ W J + P`` (exact for a
linear model). Printed per marker of the session and per σ: that estimate (``one-step``),
the same with the fit's hold rule applied inside each fold (``one-step + holds``: machine
parameters whose 2σ exceeds 20 mm / 100 mrad held at nominal, as ``fit_markers`` does)
and the K-fold held-out RMS of real refits (``refits``, what ``prior: auto`` uses), all on
the same folds. The loss is the one ``--loss auto`` settles on for that marker.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from pincal.identification import IdentificationProblem, Prior, fit_markers, is_registration
from pincal.io import read_marker_data
from pincal.measure import MarkerSetup, Measurements, marker_mechanism
from pincal.model import Mechanism
from pincal.validation import cross_validate, kfold
from pincal.workflow import PRIOR_GRID

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "docs" / "examples" / "tiago-mocap" / "measurements.csv"
#: the loss --loss auto settles on per marker of the session (docs/quality_gate.md)
LOSS = {1: "huber", 2: "linear", 3: "linear"}
BOUND = (20e-3, 0.1)  # fit_markers' hold bound on 2σ: length [m], angle [rad]


def one_step(
    mech: Mechanism,
    setup: MarkerSetup,
    meas: Measurements,
    prior: Prior,
    loss: str,
    folds: Sequence[np.ndarray],
) -> tuple[float, float]:
    """(one-step, one-step with holds) K-fold held-out RMS [m] of the fit with ``prior``."""
    fit = fit_markers(mech, setup, meas, prior=prior, loss=loss)
    res = fit.result
    x = res.full_values
    model = IdentificationProblem(fit.registration.mechanism, res.parameter_set, meas, x).model
    w = res.weighting
    assert w is not None and res.prior is not None
    model = model.with_block_std({"position": w.position_std})
    r, J, _ = model.evaluate(x, True)
    cols = np.flatnonzero(res.identified)
    J = np.asarray(J)[:, cols]
    sigma = np.asarray(model.sigma).reshape(-1)
    z = np.abs(r) / (w.f_scale if loss == "huber" else np.inf)
    weights = np.where(z > 1, 1 / np.maximum(z, 1), 1.0)  # Huber's ρ' (1: least squares)
    prec = res.prior[0][cols] ** 2
    names = [res.names[i] for i in cols]
    bound = np.array([BOUND[0] if res.units[i] == "m" else BOUND[1] for i in cols])
    bound[[is_registration(n) for n in names]] = np.inf
    pose = np.repeat(np.arange(len(meas)), 3)
    out = []
    for hold in (False, True):
        held = np.empty(len(meas))
        for f in folds:
            t = ~np.isin(pose, f)
            N = J[t].T @ (weights[t, None] * J[t]) + np.diag(prec)
            g = J[t].T @ (weights[t] * r[t]) + prec * x[cols]
            free = np.ones(cols.size, dtype=bool)
            for _ in range(6):
                d = np.where(free, 0.0, -x[cols])  # held: back to nominal
                Nf = N[np.ix_(free, free)]
                d[free] = -np.linalg.solve(Nf, g[free] + N[np.ix_(free, ~free)] @ d[~free])
                weak = np.zeros(cols.size, dtype=bool)
                weak[free] = 2 * np.sqrt(np.diag(np.linalg.inv(Nf))) > bound[free]
                if not hold or not weak.any():
                    break
                free &= ~weak
            raw = ((r + J @ d) * sigma).reshape(-1, 3)
            held[f] = np.linalg.norm(raw[f], axis=1)
        out.append(float(np.sqrt(np.mean(held**2))))
    return out[0], out[1]


def refitted(
    mech: Mechanism, setup: MarkerSetup, prior: Prior, loss: str
) -> Callable[[Measurements], Mechanism]:
    """Measurements → calibrated mechanism: the fit that ``prior: auto`` cross-validates."""
    return lambda d: fit_markers(mech, setup, d, prior=prior, loss=loss).calibrated


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--markers", type=int, nargs="+", default=[1, 2, 3], choices=[1, 2, 3])
    ap.add_argument("--seed", type=int, default=0, help="the folds' seed")
    a = ap.parse_args()
    print("K = 5 held-out RMS [mm]: one-step | one-step + holds | refits")
    for mk in a.markers:
        cols = (f"x{mk}", f"y{mk}", f"z{mk}")
        setup = MarkerSetup(link="arm_7_link", columns=cols, instrument_frame="unknown")
        mech = marker_mechanism("tiago", setup)
        read = read_marker_data(DATA, mech, setup)
        meas = read if isinstance(read, Measurements) else read.sets[0]
        folds = kfold(len(meas), 5, a.seed)
        loss = LOSS[mk]
        print(f"marker {mk} ({loss}):")
        for s in PRIOR_GRID:
            prior = Prior(s * 1e-3, s * 1e-3)
            lin, held = one_step(mech, setup, meas, prior, loss, folds)
            refit = cross_validate(refitted(mech, setup, prior, loss), meas, 5, a.seed)
            print(f"  σ {s:5g}: {lin * 1e3:6.3f} | {held * 1e3:6.3f} | {refit.rms * 1e3:6.3f}")


if __name__ == "__main__":
    main()
