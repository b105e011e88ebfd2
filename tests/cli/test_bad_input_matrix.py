"""Every subcommand against every class of bad input file: one line, exit 1, no traceback.

tests/io/test_bad_input_files.py covers the data-file options of calibrate, simulate,
compensate, view, acceptance and import-tracker; this module covers the remaining
inputs: the model argument of every command that takes one, the data file of
``validate``, the campaign file of ``run`` and the directory of ``report``.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from click.testing import CliRunner

from pincal.cli import main
from tests.cli._checks import assert_clean_failure

KINDS = ["device", "directory", "too_big", "not_utf8", "missing"]


def _bad(kind: str, path: Path, monkeypatch, header: bytes = b"") -> str:
    if kind == "device":
        return "/dev/zero"
    if kind == "directory":
        path.mkdir()
    elif kind == "too_big":
        path.write_bytes(header + b"x" * 1_200_000)
        monkeypatch.setenv("PINCAL_MAX_FILE_MB", "1")
    elif kind == "not_utf8":
        path.write_bytes(header + b"\xff\xfe\n")
    return str(path)


_MODEL_COMMANDS = {
    "info": lambda m, out: ["info", m],
    "poses": lambda m, out: ["poses", m, "--count", "3", "--out", out],
    "simulate": lambda m, out: ["simulate", m, "--random", "3", "--out", out],
    "calibrate": lambda m, out: ["calibrate", m, "--data", out, "--out", out + "d"],
    "view": lambda m, out: ["view", m, "--random", "2", "--html", out],
    "acceptance": lambda m, out: ["acceptance", m, "--out", out],
}


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("command", sorted(_MODEL_COMMANDS))
def test_model_argument(tmp_path, monkeypatch, command, kind):
    if kind == "device" and not Path("/dev/zero").exists():
        pytest.skip("no /dev/zero")
    model = _bad(kind, tmp_path / "machine.urdf", monkeypatch, b"<robot name='r'>")
    res = CliRunner().invoke(main, _MODEL_COMMANDS[command](model, str(tmp_path / "o.csv")))
    assert_clean_failure(res, Path(model).name)


@pytest.fixture(scope="module")
def calibration(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("cal")
    runner = CliRunner()
    res = runner.invoke(main, ["simulate", "wedge3", "--random", "30", "--out", str(d / "m.csv")])
    assert res.exit_code == 0, res.output
    res = runner.invoke(
        main, ["calibrate", "wedge3", "--data", str(d / "m.csv"), "--out", str(d / "cal")]
    )
    assert res.exit_code == 0, res.output
    return d / "cal"


@pytest.mark.parametrize("kind", KINDS)
def test_validate_data(tmp_path, monkeypatch, calibration, kind):
    f = _bad(kind, tmp_path / "held.csv", monkeypatch, b"# pincal measurements 1\n")
    res = CliRunner().invoke(main, ["validate", str(calibration), "--data", f])
    assert_clean_failure(res, Path(f).name)


@pytest.mark.parametrize("kind", KINDS)
def test_run_campaign_file(tmp_path, monkeypatch, kind):
    f = _bad(kind, tmp_path / "campaign.yaml", monkeypatch, b"model: wedge3\n")
    res = CliRunner().invoke(main, ["run", f, "--out", str(tmp_path / "out")])
    assert_clean_failure(res, Path(f).name)


@pytest.mark.parametrize("kind", ["device", "missing", "not_a_calibration"])
def test_report_directory(tmp_path, kind):
    if kind == "device":
        d = "/dev/zero"
    elif kind == "missing":
        d = str(tmp_path / "nothing")
    else:
        (tmp_path / "cal").mkdir()
        (tmp_path / "cal" / "calibration.json").write_bytes(b"\xff{")
        d = str(tmp_path / "cal")
    res = CliRunner().invoke(main, ["report", d, "--out", str(tmp_path / "r")])
    assert_clean_failure(res, Path(d).name)


def test_a_fifo_inside_a_calibration_directory_does_not_block(tmp_path, calibration):
    import os
    import shutil
    import subprocess
    import sys

    cal = tmp_path / "cal"
    shutil.copytree(calibration, cal)
    (cal / "identification.json").unlink()
    os.mkfifo(cal / "identification.json")
    held = calibration.parent / "m.csv"
    proc = subprocess.run(
        [sys.executable, "-m", "pincal.cli", "validate", str(cal), "--data", str(held)],
        capture_output=True,
        text=True,
        timeout=60,  # a blocking read would hang here, not fail
    )
    assert proc.returncode == 1, proc.stderr
    assert "identification.json" in proc.stderr, proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1
