"""Print the README's open-world table: what loads, calibrates, and is refused.

Run: python scripts/studies/open_world_table.py

Every machine of tests/open_world/roster.py (written here in other people's habits:
MJCF cuts and keyframes, emulated ball and U joints, robot.yaml joint kinds, 0/0 URDF
limits, springs) is loaded; a loadable one recovers a random error (σ 0.2 mm / 0.2 mrad)
on the identifiable set of its ``base`` and ``full`` presets from exact measurements at
30 random poses, from the nominal model; a refused one shows its error and message.
"""

from __future__ import annotations

import logging
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))  # the test suite's machine writers

from tests.open_world.roster import table  # noqa: E402


def main() -> None:
    logging.disable(logging.WARNING)  # the notes of each load; the table says the result
    with tempfile.TemporaryDirectory() as folder:
        for line in table(Path(folder)):
            print(line, flush=True)


if __name__ == "__main__":
    main()
