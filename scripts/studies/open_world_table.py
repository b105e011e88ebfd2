"""Print the README's open-world table: what loads, calibrates, and is refused.

Run: python scripts/studies/open_world_table.py [--only WORD ...]
(``--only``: the machines whose name contains one of the words, case-insensitive)

Every machine of tests/open_world/roster.py (written here in other people's habits:
MJCF cuts and keyframes, emulated ball and U joints, robot.yaml joint kinds, 0/0 URDF
limits, springs) is loaded; a loadable one recovers a random error (σ 0.2 mm / 0.2 mrad)
on the identifiable set of its ``base`` and ``full`` presets from exact measurements at
30 random poses, from the nominal model; a refused one shows its error and message.
"""

from __future__ import annotations

import argparse
import logging
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))  # the test suite's machine writers

from tests.open_world.roster import ROSTER, row, table  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", nargs="+", default=None, help="name fragments of machines")
    args = ap.parse_args()
    logging.disable(logging.WARNING)  # the notes of each load; the table says the result
    with tempfile.TemporaryDirectory() as folder:
        if args.only is None:
            lines = table(Path(folder))
        else:
            words = [w.lower() for w in args.only]
            picked = [mc for mc in ROSTER if any(w in mc.name.lower() for w in words)]
            lines = (row(mc, Path(folder)) for mc in picked)
        for line in lines:
            print(line, flush=True)


if __name__ == "__main__":
    main()
