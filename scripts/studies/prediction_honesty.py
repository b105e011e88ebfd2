"""Is validate's Cramér–Rao prediction honest on the closed-loop machines of issue 36?

Run: python scripts/studies/prediction_honesty.py [--draws 10] [--only NAME ...]
(NAME: a machine of tests/open_world/roster.py or a bundled model, e.g. stewart_6ups)

For each machine: the poses of ``pincal poses`` (as :func:`tests.open_world.acceptance.
noisy_campaign` chooses them), then ``--draws`` campaigns that differ only in the seed of
the instrument noise of the calibration data (``simulate --seed k``, errors seed:3 of
0.2 mm / 1 mrad on ``--params base``, the default noise); each calibration is validated on
60 fresh poses of the actual machine measured without noise, so the achieved RMS is the
calibrated model's own error, compared with the prediction's model part
(``model_rms_position_mm``). Printed per machine: the mean over the draws of
predicted / achieved with its standard error, and √(mean predicted² / mean achieved²).
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))  # the test suite's machine writers

from tests.open_world.acceptance import invoke  # noqa: E402
from tests.open_world.roster import ROSTER  # noqa: E402

MACHINES = ("MJCF delta", "rusr_ujoint", "2-RSU ankle")


def draws(model: str | Path, folder: Path, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(predicted, achieved) model RMS [mm] of ``n`` seeded calibrations."""
    invoke("poses", model, "--count", 30, "--preset", "base", "--candidates", "random:300",
           "--out", folder / "p.csv")  # fmt: skip
    errors = ("--params", "base", "--errors", "seed:3", "--error-size", "0.2,1")
    invoke("simulate", model, "--random", 60, "--seed", 9, *errors, "--noise", "0,0",
           "--out", folder / "v0.csv")  # fmt: skip
    pred, got = [], []
    for k in range(1, n + 1):
        invoke("simulate", model, "--poses", folder / "p.csv", *errors, "--seed", k,
               "--out", folder / "m.csv")  # fmt: skip
        invoke("calibrate", model, "--data", folder / "m.csv", "--params", "base",
               "--out", folder / f"cal{k}")  # fmt: skip
        doc = json.loads(invoke("validate", folder / f"cal{k}", "--data", folder / "v0.csv",
                                "--json"))  # fmt: skip
        pred.append(doc["predicted"]["model_rms_position_mm"])
        got.append(doc["after"]["rms_position_mm"])
    return np.array(pred, dtype=float), np.array(got, dtype=float)


def main() -> None:
    """Print the table."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draws", type=int, default=10)
    ap.add_argument("--only", nargs="*", default=list(MACHINES))
    args = ap.parse_args()
    logging.disable(logging.WARNING)
    print("| machine | predicted model RMS [mm] | achieved [mm] | mean pred/achieved ± SE "
          "| √(Σpred²/Σachieved²) |")  # fmt: skip
    print("|---|---|---|---|---|")
    for name in args.only:
        machine = next((m for m in ROSTER if m.name == name), None)
        with tempfile.TemporaryDirectory() as tmp:
            model = name if machine is None else machine.write(Path(tmp))  # or bundled
            pred, got = draws(model, Path(tmp), args.draws)
        r = pred / got
        se = np.std(r, ddof=1) / np.sqrt(r.size)
        rms = np.sqrt(np.sum(pred**2) / np.sum(got**2))
        print(f"| {name} | {np.mean(pred):.4f} | {np.mean(got):.4f} | {np.mean(r):.2f} ± "
              f"{se:.2f} | {rms:.2f} |", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
