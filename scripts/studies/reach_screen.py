"""Study: do the poses ``pincal poses`` designs compensate on error draws it never saw?

For each arm, ``pincal poses MODEL --count C --candidates SPEC`` (seed 0) designs the
poses with its reach screen (``--reach-errors 1,10``: three random draws of ±1 mm /
±10 mrad on the preset's parameters, and each candidate's two critical draws,
``pincal.workflow._reach_screen``); then each designed pose is compensated from its own
command (:func:`pincal.compensation.compensate`, branch changes refused, limits checked)
on ``--draws`` further uniform draws of the same size (seeds ``[100 + d, 37]``: none of
the screen's). Prints the failed compensations per arm and the design's O1.
``--critical-sigma 0`` turns the critical draws into the unmoved target (the random
draws alone: the screen before them).

    python scripts/studies/reach_screen.py [--models ur5,ur10,kinova,ur3,so100]
        [--count 30] [--candidates random:300] [--draws 40] [--critical-sigma 3]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import tempfile
import time
from pathlib import Path

import numpy as np

import pincal.workflow._reach_screen as reach
from pincal.cli import main as cli
from pincal.compensation import compensate
from pincal.io import read_commands
from pincal.model import bundled_models, example_robot_names, load_mechanism
from pincal.workflow import buildable_mask, controlled_components, pose_basis


def further_failures(model: str, commands: Path, draws: int) -> tuple[int, int, list[int]]:
    """(failed compensations, poses, indices of the poses that failed at least once)."""
    mech = load_mechanism(model)
    _, q_act = read_commands(commands, mech)
    params = pose_basis(mech, None).preset_params
    targets = [mech.forward(q) for q in q_act]
    bound = np.array([1e-3 if u == "m" else 1e-2 for u in params.units])
    bound *= buildable_mask(mech, params, q_act[:10])
    failed: dict[int, int] = {}
    for d in range(draws):
        model_d = params.apply(mech, np.random.default_rng([100 + d, 37]).uniform(-bound, bound))
        result = compensate(model_d, targets, starts=q_act, components=controlled_components(mech))
        for i in result.unreachable:
            failed[i] = failed.get(i, 0) + 1
    return sum(failed.values()), len(q_act), sorted(failed)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--models", default="ur5,ur10,kinova,ur3,so100")
    ap.add_argument("--count", type=int, default=30)
    ap.add_argument("--candidates", default="random:300")
    ap.add_argument("--draws", type=int, default=40)
    ap.add_argument("--critical-sigma", type=float, default=reach.CRITICAL_SIGMA)
    a = ap.parse_args()
    reach.CRITICAL_SIGMA = a.critical_sigma
    print(f"# {a.count} poses from {a.candidates}, critical draws {a.critical_sigma:g} σ; "
          f"each pose compensated on {a.draws} further draws of ±1 mm / ±10 mrad")  # fmt: skip
    print("| arm | poses | failed compensations | poses that failed | O1 | screen removed | s |")
    print("|---|---|---|---|---|---|---|")
    known = set(bundled_models()) | set(example_robot_names())
    with tempfile.TemporaryDirectory() as tmp:
        for model in a.models.split(","):
            if model not in known:  # e.g. so100 is not in example-robot-data 4.1
                print(f"| {model} | not in this example-robot-data | | | | | |")
                continue
            out = Path(tmp) / f"{model}.csv"
            t0 = time.process_time()
            with contextlib.redirect_stdout(io.StringIO()):  # the command's own lines
                cli(["poses", model, "--count", str(a.count), "--candidates", a.candidates,
                     "--out", str(out)], standalone_mode=False)  # fmt: skip
            seconds = time.process_time() - t0
            record = json.loads(out.with_suffix(".json").read_text())
            removed = record["screens"]["removed"]
            n_failed, n, which = further_failures(model, out.with_suffix(".commands.csv"), a.draws)
            print(f"| {model} | {n} | {n_failed} of {n * a.draws} | {which or '—'} | "
                  f"{record['indices']['O1']:.0f} | {removed.get('compensation', '—')} | "
                  f"{seconds:.1f} |", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
