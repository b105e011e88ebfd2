"""Every example-robot-data robot by name, end to end with the defaults, as a new user tries it.

Run: python scripts/studies/arms_by_name.py [--only NAME,NAME]

For each name of :func:`pincal.model.example_robot_names`, in a scratch directory:
``pincal poses NAME`` (18 poses, the default candidates and screens) → ``pincal
simulate NAME --poses … --seed 1`` (the default error draw and noise) → ``pincal
calibrate NAME --data …`` (the defaults; the quality gate decides). Printed per name:
``ok`` with the calibrated residual RMS [mm, mrad] and the command's CPU time, or the
step that stopped and its one-line error. A robot with several end effectors (legs,
two arms, hands) is refused at the first step asking for the measured frame: these are
counted, not listed.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import logging
import tempfile
import time
from pathlib import Path

from pincal.cli import main as cli
from pincal.model import example_robot_names


def campaign(name: str, folder: Path) -> str:
    """The table row's outcome for one robot."""
    stem = name.replace("/", "_")
    poses, meas, cal = folder / f"{stem}.csv", folder / f"{stem}.m.csv", folder / stem
    steps = [
        ("poses", ["poses", name, "--out", str(poses)]),
        ("simulate", ["simulate", name, "--poses", str(poses), "--out", str(meas), "--seed", "1"]),
        ("calibrate", ["calibrate", name, "--data", str(meas), "--out", str(cal), "--json"]),
    ]
    out = io.StringIO()
    for step, args in steps:
        err = io.StringIO()
        try:
            with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                cli(args, standalone_mode=False)
        except SystemExit:  # the CLI printed its one-line error
            line = [x for x in err.getvalue().splitlines() if x.startswith("pincal: error")]
            return f"{step}: {(line or ['exit without a message'])[-1][15:175]}"
    record = json.loads(out.getvalue().strip().splitlines()[-1])
    after = record["residuals"]["after"]
    return f"ok | {after['rms_position_mm']:.4f} mm, {after['rms_orientation_mrad']:.4f} mrad"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--only", default="", help="comma-separated names (default: all)")
    names = [n for n in ap.parse_args().only.split(",") if n] or example_robot_names()
    logging.disable(logging.WARNING)
    counts = {"ok": 0, "frame": 0, "other": 0}
    print("| robot | outcome | residual RMS after | CPU s |\n|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            t0 = time.process_time()
            outcome = campaign(name, Path(tmp))
            if "cannot choose the measured frame" in outcome:
                counts["frame"] += 1
                continue
            counts["ok" if outcome.startswith("ok") else "other"] += 1
            row = outcome if outcome.startswith("ok") else f"{outcome} |"
            print(f"| {name} | {row} | {time.process_time() - t0:.1f} |", flush=True)
    print(f"\n{counts['ok']} of {len(names)} calibrated; {counts['frame']} refused asking "
          f"for the measured frame (several end effectors); {counts['other']} stopped "
          "otherwise")  # fmt: skip


if __name__ == "__main__":
    main()
