"""Study: the quality gate on instrument files (ballbar, sphere probe) — false alarms, detections.

Usage:
    python scripts/studies/instrument_gate.py [--fits 60] [--poses 60] [--seed 0]
        [--cells "clean;bar scale"] [--part 0/3] [--without-refit]

Each fit: an "actual" machine drawn as ``pincal simulate`` draws it (geometric errors
uniform in ±1 mm / ±10 mrad on the model's first preset), random workspace poses (what
``pincal simulate --random N --instrument KIND`` measures), the kind's typical set-up
(:func:`pincal.identification.default_instrument`: ballbar pivot and sphere 0.1 m
below the tool points' centre, sphere radius 20 mm) read with σ = 0.01 mm (the
``simulate`` default), then what ``pincal calibrate --data FILE`` runs on an instrument
file: the readings' unit check, the joint fit (Gauss–Newton, directions placed only
beyond 20 mm / 0.1 rad held at nominal) and :func:`pincal.identification.instrument_gate`
(χ² against the file's σ, deletion outliers confirmed by a refit, solver, changes).
Faults (what the file says against what was measured):

- ``bar``: every ballbar reading × 1.01 (a bar length scaled by 1 %);
- ``radius``: the file declares the sphere radius 1 % larger than the sphere's;
- ``noise10``: the readings' noise is 10× the σ the file declares;
- ``outlier``: one reading (two) off by 0.5 mm = 50 σ (rate of *exact* naming: refused
  with cause ``outliers`` and exactly those poses named; and the seeds where the gate
  named a good reading, in any cell).

Clean, bar-scale and radius cells also count how often the fit's gauge names a constant
the file declares and the fit trusts (the bar's length scale, the sphere's radius: its
1σ from the data beyond 1e-3 of its value), refused or not: what the gauge says of a
fault no test of the residuals can see.

Rates as in ``scripts/studies/quality_gate.py``: share refused ± binomial s.e., exact
one-sided 95 % Clopper–Pearson bound; fit i of every cell uses seed ``seed + i``.
"""

from __future__ import annotations

import argparse
import dataclasses
import re
import sys
import time
from collections import Counter, defaultdict
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import pincal
from pincal.identification import (
    GateLimits,
    check_instrument_data,
    default_instrument,
    identify_instruments,
    instrument_gate,
)
from pincal.measure import Sphere, simulate_instrument
from pincal.model import load_mechanism, sample_actuators
from pincal.sensitivity import parameters

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
from scripts.studies.quality_gate import TABLE_HEAD, _rate, bound, cell_words, selected

STD = 1e-5  # m: `pincal simulate`'s default noise, the file's declared σ
ERRORS = (1.0, 10.0)  # mm, mrad: `pincal simulate`'s default error bounds
RRR3 = str(Path(__file__).resolve().parents[2] / "tests/model/machines/rrr3/rrr3.urdf")


@dataclass(frozen=True)
class Cell:
    """One row of the table: a machine, an instrument, a fault."""

    name: str
    model: str
    kind: str  # distance | sphere
    fault: str  # none | bar | radius | noise10 | outlier
    size: float = 0.0
    outliers: int = 1
    preset: str | None = None

    @property
    def clean(self) -> bool:
        return self.fault == "none"


CELLS = (
    Cell("clean, Stewart, ballbar", "stewart_6ups", "distance", "none"),
    Cell("clean, Stewart, sphere", "stewart_6ups", "sphere", "none"),
    Cell("1 % bar scale, Stewart", "stewart_6ups", "distance", "bar", 0.01),
    Cell("1 % sphere radius, Stewart", "stewart_6ups", "sphere", "radius", 0.01),
    Cell("10x noise, Stewart, ballbar", "stewart_6ups", "distance", "noise10", 10.0),
    Cell("10x noise, Stewart, sphere", "stewart_6ups", "sphere", "noise10", 10.0),
    Cell("one 0.5 mm outlier, Stewart, ballbar", "stewart_6ups", "distance", "outlier", 5e-4),
    Cell("two 0.5 mm outliers, Stewart, ballbar", "stewart_6ups", "distance", "outlier", 5e-4, 2),
    Cell("one 0.5 mm outlier, Stewart, sphere", "stewart_6ups", "sphere", "outlier", 5e-4),
    Cell("clean, 3-RRR, ballbar", RRR3, "distance", "none", preset="base"),
    Cell("1 % bar scale, 3-RRR (revolute only)", RRR3, "distance", "bar", 0.01, preset="base"),
)

_MECHS: dict[tuple[str, str | None], tuple[pincal.Mechanism, pincal.ParameterSet]] = {}


def _model(name: str, preset: str | None) -> tuple[pincal.Mechanism, pincal.ParameterSet]:
    if (name, preset) not in _MECHS:
        mech = load_mechanism(name)
        _MECHS[name, preset] = (mech, parameters(mech, preset or next(iter(mech.presets))))
    return _MECHS[name, preset]


def run_fit(
    cell: Cell, seed: int, poses: int, refit: bool = True
) -> tuple[bool, str, bool, bool, tuple[str, ...]]:
    """One fit: (refused, the refusals' kinds, the outliers named exactly, a good reading
    named, the gauge's lines of the declared constants it names, e.g.
    ``("the sphere radius: … ±239 µm …",)``).

    ``refit`` False judges outliers without the confirming refit (as before it existed).
    """
    mech, params = _model(cell.model, cell.preset)
    rng = np.random.default_rng(seed)
    bound = np.array([ERRORS[0] * 1e-3 if u == "m" else ERRORS[1] * 1e-3 for u in params.units])
    actual = params.apply(mech, rng.uniform(-bound, bound))
    q = sample_actuators(mech, poses, rng)
    inst, theta, ids = default_instrument(mech, cell.kind, q, std=STD)
    real = dataclasses.replace(inst, std=STD * cell.size) if cell.fault == "noise10" else inst
    data = simulate_instrument(actual, real, theta, q, rng, ids=ids)
    data = dataclasses.replace(data, instrument=inst)  # the file declares σ = STD
    bad: tuple[int, ...] = ()
    if cell.fault == "bar":
        data = dataclasses.replace(data, values=data.values * (1.0 + cell.size))
    elif cell.fault == "radius":
        assert isinstance(inst, Sphere)
        declared = dataclasses.replace(inst, radius=inst.radius * (1.0 + cell.size))
        data = dataclasses.replace(data, instrument=declared)  # the same readings
    elif cell.fault == "outlier":
        bad = tuple(sorted(rng.choice(len(q), cell.outliers, replace=False).tolist()))
        v = data.values.copy()
        v[list(bad)] += cell.size
        data = dataclasses.replace(data, values=v)
    limits = GateLimits()  # `pincal calibrate`'s defaults, as identify_instrument_files runs
    checked = check_instrument_data(mech, [data], ["readings"], limits)
    held = (limits.max_length_change, limits.max_angle_change)
    fit = identify_instruments(mech, params, [data], labels=["readings"], weak_bound=held)
    more = {"mech": mech, "datasets": [data], "labels": ["readings"]} if refit else {}
    verdict = instrument_gate(fit, checked, limits, **more)
    kinds = ",".join(sorted({i.kind for i in verdict.refusals}))
    exact = verdict.cause == "outliers" and verdict.outlier_poses == bad
    named = tuple(g for g in fit.gauge if "passes into the calibrated machine" in g)
    return not verdict.passed, kinds, exact, bool(set(verdict.outlier_poses) - set(bad)), named


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--fits", type=int, default=60, help="fits per cell (≥ 59 to show ≥ 95 %%)")
    ap.add_argument("--poses", type=int, default=60, help="random poses per fit")
    ap.add_argument("--seed", type=int, default=0, help="first seed")
    ap.add_argument("--cells", default=None, help="';'-separated cell-name substrings")
    ap.add_argument("--part", default=None, metavar="I/P",
                    help="run only cells I, I+P, I+2P, … (0-based) of the selection: P "
                    "processes in parallel, same seeds as one run")  # fmt: skip
    ap.add_argument("--without-refit", action="store_true",
                    help="judge outliers without the confirming refit (the gate before it)")
    a = ap.parse_args(argv)
    cells = selected(CELLS, a.cells, a.part)
    print(f"# instrument gate study: {a.fits} fits per cell, {a.poses} random poses, seeds "
          f"{a.seed}..{a.seed + a.fits - 1}, σ {STD * 1e3} mm")  # fmt: skip
    print(TABLE_HEAD)
    t0 = time.perf_counter()
    pooled = [0, 0]
    for cell in cells:
        refused, exact, seen, odd, good = 0, 0, Counter(), [], []
        named: dict[str, list[str]] = defaultdict(list)  # constant → its 1σ per fit naming it
        for i in range(a.fits):
            r, kinds, ex, g, constants = run_fit(cell, a.seed + i, a.poses, not a.without_refit)
            for line in constants:
                told = re.search(r"only to ±?([\d.]+) (µm|%)", line)
                named[line.split(":")[0]].append(f"{told[1]} {told[2]}" if told else "not told")
            refused += r
            exact += ex
            if g:
                good.append(a.seed + i)
            if kinds:
                seen[kinds] += 1
            if r == cell.clean:  # a false alarm, or a miss
                odd.append(a.seed + i)
        what, lim, note = cell_words(cell, refused, exact, seen, odd, a.fits)
        if cell.fault in ("none", "bar", "radius"):
            for k, told in named.items():
                vals = sorted(float(t.split()[0]) for t in told if t != "not told")
                span = f" (1σ {vals[0]:g}–{vals[-1]:g} {told[0].split()[1]})" if vals else ""
                note += f"; gauge names {k}: {_rate(len(told), a.fits)}{span}"
            note += "" if named else "; gauge names no declared constant"
        note += f"; good reading named: {f'seeds {good[:10]}' if good else 'none'}"
        if cell.clean:
            pooled[0] += refused
            pooled[1] += a.fits
        print(f"| {cell.name:44s} | {_rate(refused, a.fits):24s} | {lim:10s} | {what}: {note} |",
              flush=True)  # fmt: skip
    if pooled[1]:
        lim = f"≤ {100 * bound(pooled[0], pooled[1], upper=True):5.1f} %"
        print(f"| {'all clean cells':44s} | {_rate(*pooled):24s} | {lim:10s} | false alarms |")
    print(f"# {time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
