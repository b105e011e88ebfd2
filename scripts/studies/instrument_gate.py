"""A ballbar fit through the quality gate, clean and with a 1 % bar-length scale error.

Usage:
    python scripts/studies/instrument_gate.py MODEL [--seeds 5] [EXTRA OPTIONS...]
    python scripts/studies/instrument_gate.py stewart_6ups
    python scripts/studies/instrument_gate.py tests/model/machines/rrr3 --params base

Per seed S (1..--seeds): `pincal simulate MODEL --random 60 --instrument distance --seed S`
then `pincal calibrate MODEL --data …` (in-process, EXTRA passed to both), on the clean
readings and on the readings × 1.01. Prints how many calibrations were written, and per
seed (written, solver success, gate warnings, reduced χ²).
"""

from __future__ import annotations

import argparse
import json
import tempfile
from collections.abc import Callable
from pathlib import Path

from click.testing import CliRunner

from pincal.cli import main


def scaled(src: Path, dst: Path, f: Callable[[float], float]) -> Path:
    """A copy of an instrument file with every reading v replaced by f(v)."""
    head, rows = [], []
    for line in src.read_text().splitlines():
        if line.startswith("#") or (not line[:1].isdigit() and line[:1] != "-"):
            head.append(line)
            continue
        v = line.split(",")
        v[-1] = repr(f(float(v[-1])))
        rows.append(",".join(v))
    dst.write_text("\n".join(head + rows) + "\n")
    return dst


def main_(model: str, seeds: int, extra: list[str]) -> None:
    runner = CliRunner()
    out: dict[str, list] = {"clean": [], "bar scale 1.01": []}
    for seed in range(1, seeds + 1):
        d = Path(tempfile.mkdtemp())
        res = runner.invoke(main, ["simulate", model, "--random", "60", "--instrument",
                                   "distance", "--seed", str(seed), *extra,
                                   "--out", str(d / "b.csv")])  # fmt: skip
        assert res.exit_code == 0, res.output
        bar = scaled(d / "b.csv", d / "s.csv", lambda v: 1.01 * v)
        for key, path in {"clean": d / "b.csv", "bar scale 1.01": bar}.items():
            target = str(d / key.replace(" ", "_"))
            res = runner.invoke(main, ["calibrate", model, "--data", str(path), "--out",
                                       target, *extra, "--json"])  # fmt: skip
            doc = json.loads(res.stdout) if res.exit_code == 0 else {}
            warnings = [w["kind"] for w in doc.get("quality", {}).get("warnings", [])]
            out[key].append((res.exit_code == 0, doc.get("success"), warnings,
                             round(doc["reduced_chi2"], 2) if doc else None))  # fmt: skip
    for key, rows in out.items():
        print(f"{model} {key}: written {sum(r[0] for r in rows)} of {len(rows)}  {rows}")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("model")
    ap.add_argument("--seeds", type=int, default=5)
    a, extra = ap.parse_known_args()  # the rest goes to simulate and calibrate
    main_(a.model, a.seeds, extra)
