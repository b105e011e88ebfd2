"""Benchmark: realistic user operations, now against a baseline checkout, in one table.

Usage (from the checkout to measure; every output goes to one temporary directory):
    OPENBLAS_NUM_THREADS=1 python scripts/bench_realdata.py [--repeats 3] [--quick]
        [--rows tiago-run,cv,...] [--timeout 900] [--baseline DIR --label REV]
    python scripts/bench_realdata.py --profile delta [--timeout 900] [--top 20]

Rows (CPU seconds, median of ``--repeats``; the issue's target beside each):

``startup``
    ``python -m pincal.cli --help``: the import cost every command below pays.
``tiago-run``
    ``pincal run docs/examples/tiago-mocap/campaign.yaml``: 34 real motion-capture
    poses, registration + chain fit with the defaults of real data (``loss: auto``,
    ``prior: auto``: the prior's strength chosen by nested 5-fold CV), 5-fold CV, report.
``tiago-filed``
    The same campaign as issue 34 measured it (at 16cc3c9: ``loss: huber``, ``prior:
    10,10``, 5-fold CV, report), the row of its ≤ 4 s target: the example has since
    chosen its prior by nested CV, whose target is the ``prior-auto`` row's.
``cv``
    ``pincal validate CAL --cv 5 --refit`` of that calibration (made once, untimed; with
    a prior of 10 mm / 10 mrad): every fold fitted, although validate would reuse the
    cross-validation calibrate recorded (``--refit`` left out where the checkout does
    not have it: there validate always refits).
``select-model``
    ``pincal select-model tiago --link arm_7_link`` on the same marker table, the five
    default error models, 5 folds.
``prior-auto``
    The same campaign on ``../shared/realdata/tiago-qualisys/`` (beside the repository
    root, as CI lays it out; skipped with a note when absent) with ``prior: auto`` and
    no report: the prior's strength chosen by an inner 5-fold CV inside each of the 5
    outer folds (nested CV).
``ur5-body-48`` / ``ur5-marker-48``
    ``pincal calibrate ur5 --link wrist_3_link`` with the defaults (``--prior auto``,
    ``--loss auto``: the prior chosen by an inner 5-fold CV inside each of the gate's 5
    outer folds, nested CV) on a second data set that is not TIAGo's: 48 poses of a UR5
    simulated by Pinocchio alone (:mod:`tests.identification.marker_body_sim`: every
    joint placement perturbed by a random twist of ±1 mm / ±1 mrad per coordinate, noise
    0.2 mm per coordinate and 1 mrad per axis). ``ur5-body-48`` fits the 6-D body
    (positions and roll/pitch/yaw), ``ur5-marker-48`` the same table's positions only.
``delta``
    ``pincal calibrate tests/model/mjcf/delta.xml --params base`` on 30 poses written
    by ``pincal simulate`` (defaults: errors ±1 mm / ±10 mrad, noise 10 µm): the MJCF
    Delta of ball-ended parallelogram rods (two rods per arm, ``connect`` cuts to a free
    platform), as a new user writes one.
``delta-4r``
    The same on the Delta of ``tests/open_world/machines.py`` (``delta_4r``: the
    parallelograms as four-revolute loops closed by ``6d`` welds).
``ur5-socket``
    ``pincal calibrate ur5`` on ``pincal simulate ur5 --random 40 --instrument socket``
    (40 seatings in two sockets 50 mm apart, their distance declared).
``stewart-batched`` / ``stewart-joint``
    One simulated ``stewart_6ups`` pose file (60 random poses, preset ``stewart42``,
    errors ±1 mm / ±10 mrad, noise 10 µm / 20 µrad declared) fitted in-process by the
    batched route (``identify(IdentificationProblem(mech, params, meas))``) and by the
    joint route (``identify_instruments(mech, params, [meas])``: the
    ``InstrumentProblem`` of the same file); the last line gives joint / batched.

CLI rows run ``python -m pincal.cli`` as a child process and time its CPU (user +
system, ``RUSAGE_CHILDREN``), import included (the ``startup`` row); untimed set-up
(simulated data, the calibration ``cv`` validates) runs first. A row whose first
repeat exceeds ``--timeout`` wall seconds is stopped and shown as "> T s"; a calibrate
the quality gate refuses is timed all the same and marked "(refused)". Every
process runs with one BLAS thread. With ``--baseline DIR`` (another checkout, e.g.
``git worktree add --detach DIR REV``) this script's worker runs there too, with that
checkout's package and example files, and the table gives both columns and the ratio
baseline / now. Each column first copies its checkout (without ``.git``) into the
temporary directory and compiles the package's bytecode there (untimed), and its
children run from that copy: they read compiled modules as an installed package does,
and nothing is written beside the sources (the environment may well set
``PYTHONDONTWRITEBYTECODE``, which otherwise makes every child recompile pincal).

``--profile ROW`` runs one CLI row (``tiago-run``, ``cv``, ``select-model``,
``prior-auto``, ``delta``, ``ur5-socket``) once under cProfile in the checkout of
``--baseline`` (else this one) and prints the ``--top`` functions by cumulative time (all,
then pincal's library outside ``pincal/cli``) and by own time;
at ``--timeout`` the child is interrupted and the profile so far is printed.
"""

from __future__ import annotations

import argparse
import json
import os
import pstats
import resource
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SHARED_TIAGO = ROOT.parent / "shared" / "realdata" / "tiago-qualisys"
"""The real 34-pose TIAGo set beside the repository (``../shared``, as CI lays it out)."""

ROWS: dict[str, tuple[str, str]] = {
    "startup": ("startup: python -m pincal.cli --help", ""),
    "tiago-run": ("TIAGo pincal run (34 poses, defaults, CV 5, report)", ""),
    "tiago-filed": ("TIAGo run as filed (Huber, prior 10,10, CV 5, report)", "≤ 4 s"),
    "cv": ("TIAGo validate --cv 5", "≤ 1 s"),
    "select-model": ("TIAGo select-model, 5 models, CV 5", ""),
    "prior-auto": ("TIAGo run, prior auto, nested CV 5", "≤ 20 s"),
    "ur5-body-48": ("UR5 6-D body, 48 poses, prior auto, nested CV 5", "≤ 20 s"),
    "ur5-marker-48": ("UR5 marker, 48 poses, prior auto, nested CV 5", "≤ 20 s"),
    "delta": ("Delta (MJCF, ball rods) calibrate --params base", "≤ 15 s"),
    "delta-4r": ("Delta (4R parallelograms) calibrate --params base", "≤ 15 s"),
    "ur5-socket": ("UR5 socket calibrate, 40 seatings", ""),
    "stewart-batched": ("Stewart pose file, batched fit", ""),
    "stewart-joint": ("Stewart pose file, joint fit", "≤ 2× batched"),
}
"""Row key → (label, target of the issue)."""

TIMED_OUT = -1.0
"""A row's time when its first repeat ran past the timeout."""

SKIPPED = -2.0
"""A row's time when its input is absent (the shared real data)."""

FAILED = -3.0
"""A row's time when a command of it failed (its error is printed on stderr)."""


# ------------------------------------------------------------------ the child processes
def _child_env(src: Path) -> dict[str, str]:
    """Environment of a pincal child: the package in ``src``, one BLAS thread."""
    env = dict(os.environ)
    env.pop("PYTHONPYCACHEPREFIX", None)
    env.update(PYTHONPATH=str(src), OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1",
               MKL_NUM_THREADS="1")  # fmt: skip
    return env


def _children_cpu() -> float:
    """CPU time [s] (user + system) of the waited-for children of this process."""
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


class Cli:
    """Runs ``python -m pincal.cli`` children from a compiled copy of the working directory.

    Creating one copies the checkout in the working directory (without ``.git``) to
    ``tmp/src``, compiles its ``pincal`` there and changes the working directory to the
    copy: relative paths (example campaigns, test models) are the checkout's files.

    Attributes:
        tmp: the temporary directory every output goes to.
        src: the copy of the checkout the children import and run in.
        timeout: wall seconds [s] after which a child is killed (None: no limit).
    """

    def __init__(self, tmp: Path, timeout: float | None) -> None:
        self.tmp = tmp
        self.timeout = timeout
        self.src = tmp / "src"
        skip = shutil.ignore_patterns(".git", "__pycache__", "*.egg-info")
        shutil.copytree(Path.cwd(), self.src, ignore=skip)
        os.chdir(self.src)
        self.env = _child_env(self.src)
        subprocess.run([sys.executable, "-m", "compileall", "-q", "pincal"], env=self.env,
                       check=True, capture_output=True)  # fmt: skip
        self.run("--help", timed=False)  # warm the file system cache
        self._n = 0
        self.refused = 0

    def fresh(self, name: str) -> Path:
        """A new path ``tmp/<name>-<k>`` that does not exist yet."""
        self._n += 1
        return self.tmp / f"{name}-{self._n}"

    def run(self, *args: str | Path, timed: bool = True) -> float:
        """Run ``pincal ARGS``; its CPU time [s], or TIMED_OUT past the timeout.

        Raises:
            RuntimeError: the command failed (its stderr's tail in the message).
        """
        cmd = [sys.executable, "-m", "pincal.cli", *map(str, args)]
        t0 = _children_cpu()
        try:
            out = subprocess.run(cmd, env=self.env, cwd=self.src, capture_output=True, text=True,
                                 timeout=self.timeout if timed else None)  # fmt: skip
        except subprocess.TimeoutExpired:
            return TIMED_OUT
        t = _children_cpu() - t0
        if out.returncode != 0 and "QualityGateError" in out.stderr:
            self.refused += 1  # timed all the same: what the user waits for
        elif out.returncode != 0:
            tail = "\n".join(out.stderr.strip().splitlines()[-8:])
            raise RuntimeError(f"pincal {' '.join(map(str, args))} failed:\n{tail}")
        return t


def _repeat(fn: Callable[[], float], repeats: int) -> float:
    """Median of ``fn()`` [s] over repeats; TIMED_OUT as soon as one repeat times out."""
    times = []
    for _ in range(repeats):
        t = fn()
        if t == TIMED_OUT:
            return TIMED_OUT
        times.append(t)
    return statistics.median(times)


# ------------------------------------------------------------------ the set-ups of the rows
def _tiago_campaign(
    cli: Cli, data: Path, prior: str, cv: int | None, report: bool, loss: str | None = None
) -> Path:
    """The example TIAGo campaign rewritten into tmp: data file, prior, CV folds, report
    (and the loss, when given)."""
    import yaml

    doc = yaml.safe_load(Path("docs/examples/tiago-mocap/campaign.yaml").read_text())
    doc["measurements"]["file"] = str(data.resolve())
    doc["identification"]["prior"] = prior
    if loss is not None:
        doc["identification"]["loss"] = loss
    doc["validation"]["cv"] = cv
    doc["report"] = report
    path = cli.fresh("campaign").with_suffix(".yaml")
    path.write_text(yaml.safe_dump(doc, sort_keys=False), encoding="utf-8")
    return path


def _command(row: str, cli: Cli) -> tuple[str, ...] | None:
    """The timed pincal arguments of a CLI row (after its untimed set-up); None: skipped."""
    example = Path("docs/examples/tiago-mocap")
    mocap = example / "measurements.csv"
    if row == "startup":
        return ("--help",)
    if row == "tiago-run":
        return ("run", str(example / "campaign.yaml"), "--out", "{out}")
    if row == "tiago-filed":
        filed = _tiago_campaign(cli, mocap, "10,10", 5, True, loss="huber")
        return ("run", str(filed), "--out", "{out}")
    if row == "cv":
        cal = cli.fresh("tiago-cal")
        cli.run("run", _tiago_campaign(cli, mocap, "10,10", None, False), "--out", cal, timed=False)
        # a marker calibration records its gate's CV, which validate --cv reuses: --refit
        # (where the checkout has it) times the 5-fold CV itself
        refit = "--refit" in (cli.src / "pincal" / "cli" / "validate.py").read_text()
        return ("validate", str(cal), "--cv", "5", *(("--refit",) if refit else ()))
    if row == "select-model":
        return ("select-model", "tiago", "--link", "arm_7_link", "--data", str(mocap),
                "--marker-columns", "x1,y1,z1")  # fmt: skip
    if row == "prior-auto":
        shared = Path(os.environ["BENCH_SHARED_TIAGO"]) / "measurements.csv"
        if not shared.is_file():
            return None
        return ("run", str(_tiago_campaign(cli, shared, "auto", 5, False)), "--out", "{out}")
    if row in ("ur5-body-48", "ur5-marker-48"):
        sys.path.insert(0, str(cli.src))
        from tests.identification.marker_body_sim import body_poses, write_body_table

        table = cli.fresh("ur5-body").with_suffix(".csv")
        q, P, R = body_poses(48, 11, sigma_p=2e-4, sigma_r=1e-3, perturb=1e-3, truth_seed=5)
        write_body_table(table, q, P, R)
        body = ("--orientation-columns", "roll,pitch,yaw", "--orientation", "rpy-deg")
        return ("calibrate", "ur5", "--data", str(table), "--link", "wrist_3_link",
                "--length-unit", "mm", *(body if row == "ur5-body-48" else ()),
                "--out", "{out}")  # fmt: skip
    if row == "delta":
        model = "tests/model/mjcf/delta.xml"
        data = cli.fresh("delta").with_suffix(".csv")
        cli.run("simulate", model, "--random", "30", "--params", "base", "--out", data,
                timed=False)  # fmt: skip
        return ("calibrate", model, "--data", str(data), "--params", "base", "--out", "{out}")
    if row == "delta-4r":
        sys.path.insert(0, str(cli.src))
        from tests.open_world.machines import delta_4r, write_machine

        model = str(write_machine(cli.fresh("machines"), "delta4r", *delta_4r()))
        data = cli.fresh("delta4r").with_suffix(".csv")
        cli.run("simulate", model, "--random", "30", "--params", "base", "--out", data,
                timed=False)  # fmt: skip
        return ("calibrate", model, "--data", str(data), "--params", "base", "--out", "{out}")
    if row == "ur5-socket":
        data = cli.fresh("sockets").with_suffix(".csv")
        cli.run("simulate", "ur5", "--random", "40", "--instrument", "socket", "--errors",
                "seed:3", "--seed", "1", "--out", data, timed=False)  # fmt: skip
        return ("calibrate", "ur5", "--data", str(data), "--out", "{out}")
    raise ValueError(f"not a CLI row: {row}")


def _cli_row(row: str, cli: Cli, repeats: int) -> float:
    """Median CPU time [s] of a CLI row (each repeat with a fresh ``--out``)."""
    args = _command(row, cli)
    if args is None:
        return SKIPPED

    def once() -> float:
        out = str(cli.fresh(row))
        return cli.run(*(out if a == "{out}" else a for a in args))

    return _repeat(once, repeats)


def _stewart_rows(repeats: int) -> dict[str, float]:
    """Median CPU times [s] of the batched and the joint fit of one Stewart pose file."""
    import numpy as np
    from threadpoolctl import threadpool_limits

    from pincal.identification import identify, identify_instruments
    from pincal.identification.problem._identification_problem import IdentificationProblem
    from pincal.measure import simulate_measurements
    from pincal.model import load_mechanism, parameters, sample_actuators

    with threadpool_limits(1):
        nom = load_mechanism("stewart_6ups")
        ps = parameters(nom, "stewart42")
        bound = np.array([1e-3 if u == "m" else 1e-2 for u in ps.units])
        actual = ps.apply(nom, np.random.default_rng(1).uniform(-bound, bound))
        q = sample_actuators(nom, 60, np.random.default_rng(0))
        noise = {"position": 0.01, "orientation": 0.02}
        meas = simulate_measurements(actual, q, noise, np.random.default_rng(2))

        def batched() -> object:
            return identify(IdentificationProblem(nom, ps, meas))

        def joint() -> object:
            return identify_instruments(nom, ps, [meas])

        batched(), joint()  # warm-up: lazy imports, caches of the nominal model
        out: dict[str, list[float]] = {"stewart-batched": [], "stewart-joint": []}
        for _ in range(repeats):  # in turns: the same machine conditions for both
            for key, fn in (("stewart-batched", batched), ("stewart-joint", joint)):
                t0 = time.process_time()
                fn()
                out[key].append(time.process_time() - t0)
    return {k: statistics.median(v) for k, v in out.items()}


def worker(rows: list[str], repeats: int, timeout: float | None) -> dict[str, float]:
    """Time ``rows`` with the pincal of the working directory; CPU seconds per row."""
    out: dict[str, float] = {}
    with tempfile.TemporaryDirectory(prefix="bench-realdata-") as tmp:
        cli = Cli(Path(tmp), timeout)
        for row in rows:
            if row.startswith("stewart-"):
                if row not in out:
                    out |= {k: v for k, v in _stewart_rows(repeats).items() if k in rows}
                continue
            cli.refused = 0
            try:
                out[row] = _cli_row(row, cli, repeats)
                if cli.refused:
                    out[f"{row}:refused"] = float(cli.refused)
            except RuntimeError as e:
                print(e, file=sys.stderr)
                out[row] = FAILED
            print(f"  {row}: {out[row]:.2f}", file=sys.stderr, flush=True)
    return out


# ------------------------------------------------------------------ profile
def profile(checkout: Path, row: str, timeout: float | None, top: int) -> None:
    """Run one CLI row once under cProfile in ``checkout``; print the top cumulative."""
    os.chdir(checkout)
    with tempfile.TemporaryDirectory(prefix="bench-realdata-") as tmp:
        cli = Cli(Path(tmp), None)
        args = _command(row, cli)
        if args is None:
            print(f"{row}: skipped (no {os.environ['BENCH_SHARED_TIAGO']})")
            return
        stats = Path(tmp) / "profile.out"
        args = tuple(str(cli.fresh(row)) if a == "{out}" else a for a in args)
        cmd = [sys.executable, "-m", "cProfile", "-o", str(stats), "-m", "pincal.cli", *args]
        t0 = _children_cpu()
        err = Path(tmp) / "stderr.txt"
        with err.open("w") as sink:
            proc = subprocess.Popen(cmd, env=cli.env, cwd=cli.src, stdout=subprocess.DEVNULL,
                                    stderr=sink)  # fmt: skip
        try:
            proc.wait(timeout=timeout)
            # cProfile swallows SystemExit: the command's own outcome is on its stderr
            errors = [ln for ln in err.read_text().splitlines() if ln.startswith("pincal: error")]
            note = errors[-1][:100] if errors else "finished"
        except subprocess.TimeoutExpired:
            proc.send_signal(signal.SIGINT)  # cProfile writes its file on the way out
            proc.wait()
            note = f"interrupted at {timeout:g} s wall"
        print(f"pincal {' '.join(args)}  ({note}, {_children_cpu() - t0:.1f} s CPU "
              "under cProfile)")  # fmt: skip
        st = pstats.Stats(str(stats))
        print(f"\n== top {top} by cumulative time")
        st.sort_stats("cumulative").print_stats(top)
        print(f"== top {top} pincal library functions (outside pincal/cli) by cumulative time")
        st.print_stats(r"pincal/(?!cli/)", top)
        print(f"== top {top} by own time")
        st.sort_stats("tottime").print_stats(top)


# ------------------------------------------------------------------ driver
def _run(checkout: Path, rows: list[str], repeats: int, timeout: float | None) -> dict:
    """The worker's times, run in a subprocess with cwd = ``checkout``."""
    env = dict(os.environ, PYTHONPATH=str(checkout), OPENBLAS_NUM_THREADS="1",
               BENCH_SHARED_TIAGO=str(SHARED_TIAGO))  # fmt: skip
    cmd = [
        sys.executable,
        str(ROOT / "scripts" / "bench_realdata.py"),
        "--worker",
        f"--rows={','.join(rows)}",
        f"--repeats={repeats}",
        f"--timeout={timeout or 0}",
    ]
    out = subprocess.run(cmd, cwd=checkout, check=True, stdout=subprocess.PIPE, text=True,
                         env=env)  # fmt: skip
    return json.loads(out.stdout.strip().splitlines()[-1])


def _cell(t: float | None, timeout: float | None) -> str:
    """A time as the table shows it."""
    if t is None:
        return "—"
    if t == TIMED_OUT:
        return f"> {timeout:g} s"
    if t == SKIPPED:
        return "skipped"
    if t == FAILED:
        return "failed"
    return f"{t:.2f} s"


def _ratio(old: float | None, now: float | None, timeout: float | None) -> str:
    """baseline / now as the table shows it (a lower bound when the baseline timed out)."""
    if old is None or now is None or now <= 0:
        return "—"
    if old == TIMED_OUT and timeout:
        return f"> {timeout / now:.1f}×"
    return f"{old / now:.2f}×" if old > 0 else "—"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3, help="repeats per row (median)")
    ap.add_argument("--quick", action="store_true", help="one repeat")
    ap.add_argument("--rows", default=",".join(ROWS), help="comma-separated row keys")
    ap.add_argument(
        "--timeout",
        type=float,
        default=900.0,
        help="wall seconds [s] after which a CLI row stops (0: none)",
    )
    ap.add_argument("--baseline", type=Path, help="another checkout to compare")
    ap.add_argument("--label", default="baseline", help="the baseline's column label")
    ap.add_argument("--profile", metavar="ROW", help="profile one CLI row instead")
    ap.add_argument("--top", type=int, default=20, help="--profile: functions shown")
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args()
    rows = [r.strip() for r in a.rows.split(",") if r.strip()]
    if unknown := [r for r in rows if r not in ROWS]:
        ap.error(f"unknown rows {unknown}; choose from {', '.join(ROWS)}")
    repeats = 1 if a.quick else a.repeats
    timeout = a.timeout or None
    if a.worker:
        print(json.dumps(worker(rows, repeats, timeout)))
        return
    os.environ.setdefault("BENCH_SHARED_TIAGO", str(SHARED_TIAGO))
    if a.profile:
        profile((a.baseline or ROOT).resolve(), a.profile, timeout, a.top)
        return
    now = _run(ROOT, rows, repeats, timeout)
    old = _run(a.baseline.resolve(), rows, repeats, timeout) if a.baseline else None
    print(
        f"\nCPU time [s] (user + system of the pincal process, import included), median of "
        f"{repeats}; one BLAS thread; timeout {_cell(TIMED_OUT, timeout)[2:]} wall\n"
    )
    head = f"| operation | now | {a.label} | {a.label} / now | target |" if old else \
        "| operation | now | target |"  # fmt: skip
    print(head + "\n" + "|---" * (head.count("|") - 1) + "|")
    for row in rows:
        label, target = ROWS[row]
        t = now.get(row)
        cells = [label, _cell(t, timeout) + (" (refused)" if f"{row}:refused" in now else "")]
        if old is not None:
            b = old.get(row)
            b_cell = _cell(b, timeout) + (" (refused)" if f"{row}:refused" in old else "")
            cells += [b_cell, _ratio(b, t, timeout)]
        print("| " + " | ".join([*cells, target]) + " |")
    if {"stewart-batched", "stewart-joint"} <= now.keys():
        line = f"\njoint / batched fit of the Stewart pose file: now " \
            f"{now['stewart-joint'] / now['stewart-batched']:.2f}×"  # fmt: skip
        if old is not None and {"stewart-batched", "stewart-joint"} <= old.keys():
            line += f", {a.label} {old['stewart-joint'] / old['stewart-batched']:.2f}×"
        print(line + " (target ≤ 2×)")
    if SKIPPED in now.values():
        print(f"\nskipped: prior-auto needs {SHARED_TIAGO} (../shared beside the clone)")


if __name__ == "__main__":
    main()
