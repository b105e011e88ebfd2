"""The calibration directory is replaced as a whole, by one writer at a time.

Kills are simulated at the exact instants that matter (``os._exit`` inside a child
process, which like SIGKILL runs no cleanup) and, in the slow test, with real
``kill -9`` of `pincal calibrate` at timed instants.
"""

from __future__ import annotations

import fcntl
import hashlib
import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

from pincal.errors import CalibrationDirectoryError
from pincal.identification import identify
from pincal.io import (
    MANIFEST,
    calibration_lock,
    read_calibration,
    write_calibration,
    write_measurements,
)
from pincal.measure import NoiseModel, simulate_measurements
from pincal.model import load_mechanism, parameters, sample_actuators

ROOT = Path(__file__).resolve().parents[2]


def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(ROOT)}


@pytest.fixture(scope="module")
def data_file(tmp_path_factory) -> Path:
    nominal = load_mechanism("wedge3")
    params = parameters(nominal, "patent")
    rng = np.random.default_rng(5)
    actual = params.apply(nominal, rng.normal(0, 2e-4, len(params)))
    meas = simulate_measurements(actual, sample_actuators(nominal, 12, rng),
                                 NoiseModel(0.005, 0.01), rng)  # fmt: skip
    return write_measurements(tmp_path_factory.mktemp("data") / "m.csv", meas)


@pytest.fixture(scope="module")
def result(data_file):
    from pincal.io import read_measurements

    nominal = load_mechanism("wedge3")
    return identify(nominal, parameters(nominal, "patent"), read_measurements(data_file, nominal))


def consistent_set(d: Path) -> dict:
    """Assert ``d`` is one complete set (every manifest SHA-256 matches); its manifest."""
    manifest = json.loads((d / MANIFEST).read_text())
    for name, digest in manifest["files"].items():
        assert hashlib.sha256((d / name).read_bytes()).hexdigest() == digest, name
    assert sorted(p.name for p in d.iterdir()) == sorted([*manifest["files"], MANIFEST])
    read_calibration(d)  # the reader agrees
    return manifest


def strays(parent: Path) -> list[str]:
    """Temporaries of any pincal writer under ``parent`` (none after a finished run)."""
    return sorted(str(p.relative_to(parent)) for p in parent.rglob("*")
                  if ".pincal-" in p.name or p.name.endswith(".tmp"))  # fmt: skip


_KILLER = textwrap.dedent(
    """
    import os, sys, json
    import pincal.io._atomic as at
    import pincal.io._calibration_write as cd
    from pincal.identification import identify
    from pincal.io import read_measurements, write_calibration
    from pincal.model import load_mechanism, parameters

    where, out, data = sys.argv[1:4]
    if where == "while-writing":
        real = cd.atomic_write_text
        def patched(path, text):
            real(path, text[: len(text) // 2])
            os._exit(9)
        cd.atomic_write_text = patched
    elif where == "before-swap":
        at.exchange_paths = lambda a, b: os._exit(9)
    elif where == "after-swap":
        real_x = at.exchange_paths
        def after(a, b):
            real_x(a, b)
            os._exit(9)
        at.exchange_paths = after
    nominal = load_mechanism("wedge3")
    params = parameters(nominal, "patent")
    res = identify(nominal, params, read_measurements(data, nominal))
    write_calibration(out, res, model_source="wedge3", texts={"report.txt": "new run\\n"})
    """
)


@pytest.mark.parametrize("where", ["while-writing", "before-swap", "after-swap"])
def test_killed_writer_leaves_old_or_new_set_and_next_run_cleans(
    where, result, data_file, tmp_path
):
    out = tmp_path / "cal"
    write_calibration(out, result, model_source="wedge3", texts={"report.txt": "old run\n"})
    proc = subprocess.run([sys.executable, "-c", _KILLER, where, str(out), str(data_file)],
                          env=_env(), capture_output=True, text=True, timeout=300)  # fmt: skip
    assert proc.returncode == 9, proc.stderr
    consistent_set(out)
    report = (out / "report.txt").read_text()
    assert report == ("new run\n" if where == "after-swap" else "old run\n")
    assert strays(tmp_path)  # the killed run left its temporaries (and its lock file)
    write_calibration(out, result, model_source="wedge3", texts={"report.txt": "third\n"})
    consistent_set(out)
    assert (out / "report.txt").read_text() == "third\n"
    assert strays(tmp_path) == []


def test_second_writer_is_refused_while_the_lock_is_held(result, tmp_path):
    out = tmp_path / "cal"
    write_calibration(out, result, model_source="wedge3")
    before = consistent_set(out)
    lock = tmp_path / ".cal.pincal-lock"
    fd = os.open(lock, os.O_RDWR | os.O_CREAT)  # another process' writer, as the kernel sees it
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        with pytest.raises(CalibrationDirectoryError, match="another pincal is writing") as e:
            write_calibration(out, result, model_source="wedge3")
        assert str(out) in str(e.value) and "--out" in str(e.value)
    finally:
        os.close(fd)
    assert consistent_set(out) == before
    write_calibration(out, result, model_source="wedge3")  # released: writes again
    assert not lock.exists() and strays(tmp_path) == []


def test_lock_is_reentrant_in_one_process(result, tmp_path):
    out = tmp_path / "cal"
    with calibration_lock(out):
        write_calibration(out, result, model_source="wedge3")  # the CLI holds it around this
        assert (tmp_path / ".cal.pincal-lock").exists()
    assert not (tmp_path / ".cal.pincal-lock").exists()
    consistent_set(out)


def _calibrate(out: Path, data: Path) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "pincal.cli", "calibrate", "wedge3", "--data", str(data),
         "--params", "patent", "--out", str(out)],
        env=_env(), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip


def test_cli_calibrate_refuses_a_directory_another_pincal_is_writing(data_file, tmp_path):
    out = tmp_path / "cal"
    with calibration_lock(out):  # this process is "the other pincal"
        proc = _calibrate(out, data_file)
        _, err = proc.communicate(timeout=300)
    assert proc.returncode == 1
    line = err.strip().splitlines()[-1]
    assert line.startswith("pincal: error: CalibrationDirectoryError: another pincal is writing")
    assert "Traceback" not in err and not out.exists()


def test_two_concurrent_calibrate_runs_one_directory(data_file, tmp_path):
    out = tmp_path / "cal"
    procs = [_calibrate(out, data_file) for _ in range(2)]
    results = [(p.wait(timeout=300), p.stderr.read()) for p in procs]  # type: ignore[union-attr]
    codes = sorted(rc for rc, _ in results)
    assert codes in ([0, 0], [0, 1]), results
    for rc, err in results:
        if rc == 1:
            assert "another pincal is writing" in err and "Traceback" not in err
    consistent_set(out)
    assert strays(tmp_path) == []


@pytest.mark.slow
def test_timed_kill_9_of_cli_calibrate_never_leaves_a_mixed_set(data_file, tmp_path):
    out = tmp_path / "cal"
    t0 = time.perf_counter()
    assert _calibrate(out, data_file).wait(timeout=300) == 0
    full = time.perf_counter() - t0
    consistent_set(out)
    rng = np.random.default_rng(0)
    for delay in np.sort(rng.uniform(0.5 * full, 1.1 * full, 8)):
        proc = _calibrate(out, data_file)
        time.sleep(delay)
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=60)
        if out.exists():
            consistent_set(out)
    assert _calibrate(out, data_file).wait(timeout=300) == 0
    consistent_set(out)
    assert strays(tmp_path) == []


def test_exchange_paths_swaps_two_directories(tmp_path):
    from pincal.io._atomic import exchange_paths

    a, b = tmp_path / "a", tmp_path / "b"
    a.mkdir()
    b.mkdir()
    (a / "x").write_text("a")
    (b / "x").write_text("b")
    if not exchange_paths(a, b):
        pytest.skip("no renameat2(RENAME_EXCHANGE) here")
    assert (a / "x").read_text() == "b" and (b / "x").read_text() == "a"


def test_without_atomic_exchange_the_fallback_still_replaces_whole(
    result, tmp_path, monkeypatch
):
    out = tmp_path / "cal"
    write_calibration(out, result, model_source="wedge3", texts={"report.txt": "old\n"})
    monkeypatch.setattr("pincal.io._atomic.exchange_paths", lambda a, b: False)
    write_calibration(out, result, model_source="wedge3", texts={"report.txt": "new\n"})
    consistent_set(out)
    assert (out / "report.txt").read_text() == "new\n" and strays(tmp_path) == []


def test_single_file_temporaries_of_a_killed_writer_are_removed(tmp_path):
    from pincal.io import atomic_write_text

    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    stale = tmp_path / f".m.csv.{dead.pid}.abc123.tmp"  # what a SIGKILLed writer leaves
    stale.write_text("half")
    mine = tmp_path / f".m.csv.{os.getpid()}.zzz.tmp"  # a live writer's: kept
    mine.write_text("busy")
    other = tmp_path / ".n.csv.1.x.tmp"  # another file's: not ours to judge
    other.write_text("x")
    atomic_write_text(tmp_path / "m.csv", "data\n")
    assert not stale.exists() and mine.exists() and other.exists()
    assert (tmp_path / "m.csv").read_text() == "data\n"


def test_a_directory_its_reader_refuses_never_replaces_a_good_one(tmp_path, data_file, result,
                                                                   monkeypatch):  # fmt: skip
    """Read back before the swap: a written set the reader refuses (here: no parameters, as
    a σ of 1e300 once produced) leaves the good calibration in place, and no temporaries."""
    import pincal.io._calibration_write as cw

    out = tmp_path / "cal"
    write_calibration(out, result, model_source="wedge3", data_files=[data_file])
    before = consistent_set(out)
    real = cw.result_to_dict

    def emptied(res, notes):
        return {**real(res, notes), "parameters": []}

    monkeypatch.setattr(cw, "result_to_dict", emptied)
    with pytest.raises(CalibrationDirectoryError, match="'parameters' must be a non-empty list"):
        write_calibration(out, result, model_source="wedge3", data_files=[data_file])
    assert consistent_set(out) == before
    assert strays(tmp_path) == []
