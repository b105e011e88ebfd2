"""A noisy campaign through the command line on every loadable machine of the roster.

Run: python scripts/studies/open_world_campaigns.py [--poses 30] [--only NAME]

Issue 36 asks that a noisy CLI campaign on a machine pincal has never seen —
``info → poses → simulate → calibrate → validate`` with the defaults — reaches the
Cramér–Rao prediction within 2.5×. For each machine of tests/open_world/roster.py that
loads, :func:`tests.open_world.acceptance.noisy_campaign` (seeded errors of 0.2 mm /
1 mrad on ``--params base``, the default noise 0.01 mm / 0.02 mrad, validation on 60
fresh poses). Printed per machine: the validation RMS after calibration, the Cramér–Rao
prediction with the instrument noise (position [mm], or orientation [mrad] for a machine
measuring none) and their ratio; a failed step or a withheld prediction says why.
"""

from __future__ import annotations

import argparse
import logging
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))  # the test suite's machine writers

from pincal.errors import PincalError  # noqa: E402
from pincal.model import load_mechanism  # noqa: E402
from tests.open_world.acceptance import noisy_campaign, prediction_ratio  # noqa: E402
from tests.open_world.roster import ROSTER, Machine  # noqa: E402


def line(machine: Machine, folder: Path, poses: int) -> str:
    """The machine's table row."""
    head = f"| {machine.name} |"
    try:
        model = machine.write(folder)
        load_mechanism(model)
    except PincalError as exc:
        return f"{head} refused at load ({type(exc).__name__}) | | | |"
    try:
        after, predicted, unit = prediction_ratio(noisy_campaign(model, folder, poses))
    except AssertionError as exc:
        last = str(exc).strip().splitlines()
        return f"{head} failed: {last[-1] if last else '?'} | | | |"
    if predicted is None:
        return f"{head} {after:.4f} {unit} | withheld | | |"
    ok = "✓" if after <= 2.5 * predicted else "✗"
    return f"{head} {after:.4f} {unit} | {predicted:.4f} {unit} | {after / predicted:.2f} | {ok} |"


def main() -> None:
    """Print the table."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--poses", type=int, default=30)
    ap.add_argument("--only", default=None, help="one roster machine by name")
    args = ap.parse_args()
    logging.disable(logging.WARNING)
    print("| machine | validation RMS after | Cramér–Rao with noise | ratio | ≤ 2.5× |")
    print("|---|---|---|---|---|")
    for i, machine in enumerate(ROSTER):
        if args.only and machine.name != args.only:
            continue
        with tempfile.TemporaryDirectory() as tmp:
            folder = Path(tmp) / f"m{i}"
            folder.mkdir()
            print(line(machine, folder, args.poses), flush=True)


if __name__ == "__main__":
    main()
