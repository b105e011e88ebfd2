"""Study: how often the quality gate refuses clean data, and how often it sees a fault.

Usage:
    python scripts/studies/quality_gate.py [--fits 20] [--poses 50] [--seed 0]
        [--cells "clean, Stewart;1 % leg gain"] [--part 0/3] [--jobs 2 | --scheduler local:2]

Each fit: an "actual" machine drawn as ``pincal simulate`` draws it (geometric errors
uniform in ±1 mm / ±10 mrad on the model's first preset), random workspace poses, noise
0.01 mm / 0.05 mrad (the ``simulate`` default), identification with Gauss–Newton
(``pincal calibrate``'s default) and :func:`pincal.identification.check_quality` with
the mechanism and the measurements — the checks ``pincal calibrate`` runs. Faults:

- ``scale``: measured positions × (1 + s) about the world origin (a tracker scale);
- ``gain``: the actuator readings are the true values / 1.01 (a 1 % leg-length gain
  the model does not have);
- ``bend``: x grows with the square of the tool's z, by 0.1 mm from the middle of the
  campaign's z range to its ends (a bent guide: only the coordinate-trend probe sees
  it);
- ``noise10``: the simulated noise is 10× the noise the file declares (or, with the
  noise estimated, 10× the laser-tracker profile's limit check);
- ``outlier``: one pose of 30 (two of 40 on wedge3) moved by 5 mm along x (rate of
  *exact* naming: refused with cause ``outliers`` and exactly those poses named).

A cell's rate is the share of refused fits (false alarms on clean cells, detections on
fault cells) with its binomial standard error √(p(1−p)/n) and its exact one-sided 95 %
(Clopper–Pearson) bound: a lower bound for a detection rate, an upper bound for a
false-alarm rate (k = 0 of n: 1 − 0.05^(1/n); 0 misses in 59 fits bound the detection
rate above 95 %). The last line pools the clean cells. Seeded: fit i of every cell uses
seed ``seed + i`` for the machine, the poses and the noise; missed (or falsely refused)
seeds are listed. A cell's fits run through :class:`pincal.executor.Executor` (``--jobs``
local processes, or a Dask ``--scheduler``): the table does not depend on either.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import time
from collections import Counter
from dataclasses import dataclass

import numpy as np

import pincal
from pincal.executor import Executor
from pincal.identification import check_quality, identify
from pincal.model import load_mechanism, parameters, sample_actuators

NOISE = (0.01, 0.05)  # mm, mrad: `pincal simulate`'s default
ERRORS = (1.0, 10.0)  # mm, mrad: `pincal simulate`'s default error bounds


@dataclass(frozen=True)
class Cell:
    """One row of the table: a machine, a fault, declared or estimated noise."""

    name: str
    model: str
    fault: str  # none | scale | gain | bend | noise10 | outlier
    size: float
    declared: bool
    profile: str | None = None
    poses: int | None = None  # None: --poses
    outliers: int = 1  # poses moved by the outlier fault

    @property
    def clean(self) -> bool:
        return self.fault == "none"


CELLS = (
    Cell("clean, Stewart, declared", "stewart_6ups", "none", 0.0, True),
    Cell("clean, Stewart, estimated", "stewart_6ups", "none", 0.0, False),
    Cell("clean, Stewart, estimated, tracker", "stewart_6ups", "none", 0.0, False,
         "laser-tracker"),
    Cell("clean, hexaslide, declared", "hexaslide_6pus", "none", 0.0, True),
    Cell("clean, hexaslide, estimated", "hexaslide_6pus", "none", 0.0, False),
    Cell("1 % scale, Stewart, estimated", "stewart_6ups", "scale", 0.01, False),
    Cell("1 % scale, Stewart, declared", "stewart_6ups", "scale", 0.01, True),
    Cell("1 % leg gain, Stewart, estimated", "stewart_6ups", "gain", 0.01, False),
    Cell("1 % leg gain, Stewart, declared", "stewart_6ups", "gain", 0.01, True),
    Cell("1 % scale, hexaslide, declared", "hexaslide_6pus", "scale", 0.01, True),
    Cell("1 % scale, hexaslide, estimated", "hexaslide_6pus", "scale", 0.01, False),
    Cell("0.1 % scale, Stewart, declared", "stewart_6ups", "scale", 0.001, True),
    Cell("0.1 % scale, Stewart, estimated", "stewart_6ups", "scale", 0.001, False),
    Cell("clean, wedge3, 40 poses, estimated", "wedge3", "none", 0.0, False, poses=40),
    Cell("0.1 mm z² bend, Stewart, declared", "stewart_6ups", "bend", 1e-4, True),
    Cell("0.1 mm z² bend, Stewart, estimated", "stewart_6ups", "bend", 1e-4, False),
    Cell("10x noise, Stewart, declared", "stewart_6ups", "noise10", 10.0, True),
    Cell("10x noise, Stewart, estimated, tracker", "stewart_6ups", "noise10", 10.0, False,
         "laser-tracker"),
    Cell("one 5 mm outlier in 30, Stewart, declared", "stewart_6ups", "outlier", 5e-3, True,
         poses=30),
    Cell("one 5 mm outlier in 30, Stewart, estimated", "stewart_6ups", "outlier", 5e-3, False,
         poses=30),
    Cell("two 5 mm outliers in 40, wedge3, estimated", "wedge3", "outlier", 5e-3, False,
         poses=40, outliers=2),
)  # fmt: skip

_MECHS: dict[str, tuple[pincal.Mechanism, pincal.ParameterSet]] = {}


def _model(name: str) -> tuple[pincal.Mechanism, pincal.ParameterSet]:
    if name not in _MECHS:
        mech = load_mechanism(name)
        _MECHS[name] = (mech, parameters(mech, next(iter(mech.presets), "full")))
    return _MECHS[name]


def run_fit(cell: Cell, seed: int, poses: int) -> tuple[bool, str, bool]:
    """One fit: (refused, the refusals' kinds, the outlier named exactly)."""
    mech, params = _model(cell.model)
    rng = np.random.default_rng(seed)
    bound = np.array([ERRORS[0] * 1e-3 if u == "m" else ERRORS[1] * 1e-3 for u in params.units])
    actual = params.apply(mech, rng.uniform(-bound, bound))
    q = sample_actuators(mech, cell.poses or poses, rng)
    factor = cell.size if cell.fault == "noise10" else 1.0
    sim = pincal.NoiseModel(NOISE[0] * factor, NOISE[1] * factor)
    meas = pincal.simulate_measurements(actual, q, sim, rng)
    meas = dataclasses.replace(meas, noise=pincal.NoiseModel(*NOISE) if cell.declared else None)
    bad: tuple[int, ...] = ()
    if cell.fault == "scale":
        meas = dataclasses.replace(meas, positions=meas.positions * (1.0 + cell.size))
    elif cell.fault == "gain":
        meas = dataclasses.replace(meas, q_act=meas.q_act / (1.0 + cell.size))
    elif cell.fault == "bend":  # x grows with z²: no scale, gain or drift
        pos = meas.positions.copy()
        z = pos[:, 2]
        pos[:, 0] += cell.size * 4 * ((z - z.min()) / (z.max() - z.min()) - 0.5) ** 2
        meas = dataclasses.replace(meas, positions=pos)
    elif cell.fault == "outlier":
        bad = tuple(sorted(rng.choice(len(meas), cell.outliers, replace=False).tolist()))
        pos = meas.positions.copy()
        pos[list(bad), 0] += cell.size
        meas = dataclasses.replace(meas, positions=pos)
    result = identify(mech, params, meas)
    verdict = check_quality(result, meas, mech=mech, instrument=cell.profile)
    kinds = ",".join(sorted({i.kind for i in verdict.refusals}))
    exact = verdict.cause == "outliers" and verdict.outlier_poses == bad
    return not verdict.passed, kinds, exact


def _fit_item(item: tuple[Cell, int, int]) -> tuple[bool, str, bool]:
    """One fit as an executor item: ``run_fit(cell, seed, poses)``."""
    return run_fit(*item)


def cell_fits(ex: Executor, cell: Cell, seeds: range, poses: int) -> list[tuple[bool, str, bool]]:
    """``run_fit`` of ``cell`` at every seed, through the executor (in seed order)."""
    items = [(cell, seed, poses) for seed in seeds]
    return ex.map(_fit_item, items, progress=cell.name).values()


def _rate(k: int, n: int) -> str:
    p = k / n if n else float("nan")
    se = math.sqrt(p * (1 - p) / n) if n else float("nan")
    return f"{k:3d}/{n:<3d} {100 * p:5.1f} % ± {100 * se:4.1f}"


def bound(k: int, n: int, upper: bool, level: float = 0.95) -> float:
    """Exact one-sided Clopper–Pearson bound of a binomial rate from k of n."""
    from scipy import stats

    if upper:
        return 1.0 if k >= n else float(stats.beta.ppf(level, k + 1, n - k))
    return 0.0 if k <= 0 else float(stats.beta.ppf(1 - level, k, n - k + 1))


def selected(cells: tuple, keys: str | None, part: str | None) -> tuple:
    """The cells whose name contains one of the ';'-separated ``keys``, then part I/P."""
    if keys:
        words = [k.strip() for k in keys.split(";")]
        cells = tuple(c for c in cells if any(k in c.name for k in words))
    if part:
        i, p = (int(v) for v in part.split("/"))
        cells = cells[i::p]
    return cells


#: the header of the studies' tables (cell, rate, bound, what was seen)
TABLE_HEAD = (f"| {'cell':44s} | {'refused (rate ± s.e.)':24s} | 95 % bound | refusals seen |\n"
              f"|{'-' * 46}|{'-' * 26}|------------|---|")  # fmt: skip


def cell_words(
    cell: Cell, refused: int, exact: int, seen: Counter, odd: list[int], n: int
) -> tuple[str, str, str]:
    """(what the rate counts, its one-sided 95 % bound, the note) of a cell's row."""
    what = "false alarms" if cell.clean else "detected"
    lim = f"{'≤' if cell.clean else '≥'} {100 * bound(refused, n, upper=cell.clean):5.1f} %"
    note = ", ".join(f"{k} ×{c}" for k, c in seen.most_common(3)) or "—"
    if odd:
        note += f"; {'refused' if cell.clean else 'missed'}: seeds {odd[:10]}"
    if cell.fault == "outlier":
        note += f"; named exactly: {_rate(exact, n)}"
    return what, lim, note


def _row(cell: Cell, fits: list[tuple[bool, str, bool]], seeds: range) -> tuple[int, int]:
    """Print the cell's row; (false alarms, fits) for the pooled clean row, else (0, 0)."""
    refused, exact, seen, odd = 0, 0, Counter(), []
    for seed, (r, kinds, ex) in zip(seeds, fits, strict=True):
        refused += r
        exact += ex
        if kinds:
            seen[kinds] += 1
        if r == cell.clean:  # a false alarm, or a miss
            odd.append(seed)
    n = len(fits)
    what, lim, note = cell_words(cell, refused, exact, seen, odd, n)
    print(f"| {cell.name:44s} | {_rate(refused, n):24s} | {lim:10s} | {what}: {note} |",
          flush=True)  # fmt: skip
    return (refused, n) if cell.clean else (0, 0)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--fits", type=int, default=60, help="fits per cell (≥ 59 to show ≥ 95 %%)")
    ap.add_argument("--poses", type=int, default=50, help="random poses per fit")
    ap.add_argument("--seed", type=int, default=0, help="first seed")
    ap.add_argument("--cells", default=None, help="';'-separated cell-name substrings")
    ap.add_argument("--part", default=None, metavar="I/P",
                    help="run only cells I, I+P, I+2P, … (0-based) of the selection: P "
                    "processes in parallel, same seeds as one run")  # fmt: skip
    ap.add_argument("--jobs", type=int, default=1, help="local processes (default 1)")
    ap.add_argument("--scheduler", default=None,
                    help="a Dask scheduler: local:N or tcp://HOST:PORT")  # fmt: skip
    a = ap.parse_args(argv)
    cells = selected(CELLS, a.cells, a.part)
    print(f"# quality gate study: {a.fits} fits per cell, {a.poses} poses, seeds "
          f"{a.seed}..{a.seed + a.fits - 1}, noise {NOISE[0]} mm / {NOISE[1]} mrad")  # fmt: skip
    print(TABLE_HEAD)
    t0 = time.perf_counter()
    pooled = [0, 0]
    seeds = range(a.seed, a.seed + a.fits)
    with Executor(a.scheduler, a.jobs) as executor:  # run as a program: __main__'s functions
        for cell in cells:
            k, n = _row(cell, cell_fits(executor, cell, seeds, a.poses), seeds)
            pooled = [pooled[0] + k, pooled[1] + n]
    if pooled[1]:
        lim = f"≤ {100 * bound(pooled[0], pooled[1], upper=True):5.1f} %"
        print(f"| {'all clean cells':44s} | {_rate(*pooled):24s} | {lim:10s} | false alarms |")
    print(f"# {time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
