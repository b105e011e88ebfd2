"""Study: the quality gate on socket files — clean campaigns, and a wrong joint reference.

Usage:
    python scripts/studies/socket_gate.py [--model ur5] [--fits 30] [--poses 40] [--seed 0]

Per fit i (seed ``seed + i``), what a user runs: ``pincal simulate MODEL --random POSES
--instrument socket --errors seed:S --seed S`` (errors uniform in ±1 mm / ±10 mrad, a
ball seated in two sockets 50 mm apart with their known distance, σ 0.01 mm), then
``pincal calibrate MODEL --data FILE`` on

- ``clean``: the file as simulated (a refusal is a false alarm);
- ``home declared``: the same absolute readings under ``# joint_reference: home``;
- ``home undeclared``: the readings written relative to the home pose, no header.

Each row: refused (rate ± binomial s.e.), the exact one-sided 95 % Clopper–Pearson
bound, the causes named and, for the wrong references, the largest parameter change the
gate reported. Nothing is written outside a temporary directory.
"""

from __future__ import annotations

import argparse
import re
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

from click.testing import CliRunner

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # this checkout's pincal
from pincal.cli import main as cli
from pincal.model import load_mechanism
from scripts.studies.quality_gate import TABLE_HEAD, _rate, bound

CASES = ("clean", "home declared", "home undeclared")


def _variant(src: Path, dst: Path, home: list[float], case: str) -> Path:
    """``src`` as ``case`` says (see the module doc)."""
    lines = src.read_text().splitlines()
    k = next(i for i, ln in enumerate(lines) if not ln.startswith("#"))
    if case == "clean":
        return src
    if case == "home declared":
        dst.write_text("\n".join([*lines[:k], "# joint_reference: home", *lines[k:]]) + "\n")
        return dst
    rows = []
    for ln in lines[k + 1 :]:
        cells = ln.split(",")
        q = [f"{float(v) - h:.17g}" for v, h in zip(cells[:-1], home, strict=True)]
        rows.append(",".join([*q, cells[-1]]))
    dst.write_text("\n".join([*lines[: k + 1], *rows]) + "\n")
    return dst


def run_fit(model: str, poses: int, seed: int, work: Path) -> dict[str, tuple[bool, str, str]]:
    """Per case: (refused, cause or '', the refusal's worst change or '')."""
    mech = load_mechanism(model)
    home = [float(v) for v in mech.actuators_of(mech.q_home)]
    run = CliRunner()
    src = work / f"s{seed}.csv"
    sim = ["simulate", model, "--random", str(poses), "--instrument", "socket"]
    r = run.invoke(cli, [*sim, "--errors", f"seed:{seed}", "--seed", str(seed), "--out", str(src)])
    if r.exit_code != 0:
        raise RuntimeError(r.output)
    out = {}
    for case in CASES:
        data = _variant(src, work / f"{case.replace(' ', '_')}{seed}.csv", home, case)
        r = run.invoke(cli, ["calibrate", model, "--data", str(data), "--out",
                             str(work / f"cal_{seed}_{case.replace(' ', '_')}")])  # fmt: skip
        last = r.output.strip().splitlines()[-1] if r.output.strip() else ""
        cause = re.search(r"Likely cause: ([^—.]+)", last)
        worst = re.search(r"\(worst ([^;)]+)", last)
        out[case] = (r.exit_code != 0, cause.group(1).strip() if cause else last[:60] * (
            r.exit_code != 0), worst.group(1) if worst else "")  # fmt: skip
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--model", default="ur5")
    ap.add_argument("--fits", type=int, default=30)
    ap.add_argument("--poses", type=int, default=40, help="random poses per file")
    ap.add_argument("--seed", type=int, default=0, help="first seed")
    a = ap.parse_args(argv)
    t0 = time.process_time()
    results: dict[str, list[tuple[bool, str, str]]] = {c: [] for c in CASES}
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(a.fits):
            for case, res in run_fit(a.model, a.poses, a.seed + i, Path(tmp)).items():
                results[case].append(res)
    print(f"# socket gate study: {a.model}, {a.fits} files of {a.poses} random poses, seeds "
          f"{a.seed}..{a.seed + a.fits - 1}")  # fmt: skip
    print(TABLE_HEAD)
    for case in CASES:
        rows = results[case]
        k, n = sum(r[0] for r in rows), len(rows)
        causes = Counter(r[1] for r in rows if r[0])
        seen = ", ".join(f"{c} ×{m}" for c, m in causes.most_common()) or "—"
        if case == "clean":
            cell = f"{_rate(k, n)}   | ≤ {100 * bound(k, n, True):5.1f} %  | false alarms: {seen}"
        else:
            worst = "; ".join(r[2] for r in rows[:3] if r[2])
            cell = (f"{_rate(k, n)}   | ≥ {100 * bound(k, n, False):5.1f} %  | causes: {seen}; "
                    f"worst change, first seeds: {worst}")  # fmt: skip
        print(f"| {case:44s} | {cell} |")
    print(f"# {time.process_time() - t0:.0f} s CPU")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
