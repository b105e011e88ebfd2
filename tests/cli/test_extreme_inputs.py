"""Inputs that used to end in a traceback: each is now one line naming what was wrong."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from pincal.cli import _limits, main
from pincal.errors import BadValueError
from pincal.io import read_measurement_file
from pincal.model import load_mechanism

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def measured(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("extreme")
    res = CliRunner().invoke(main, ["simulate", "wedge3", "--random", "60",
                                    "--out", str(d / "m.csv")])  # fmt: skip
    assert res.exit_code == 0, res.output
    return d / "m.csv"


def _one_line(res, code: int = 1) -> str:
    assert res.exit_code == code, res.output
    assert "Traceback" not in res.output
    return res.stderr.strip().splitlines()[-1]


@pytest.mark.parametrize("column", [3, 4, 5])
def test_a_1e308_coordinate_names_row_and_column(measured, tmp_path, column):
    lines = measured.read_text().splitlines()
    head = next(i for i, t in enumerate(lines) if not t.startswith("#"))
    cells = lines[head + 1].split(",")
    cells[column] = "1e308"
    lines[head + 1] = ",".join(cells)
    f = tmp_path / "far.csv"
    f.write_text("\n".join(lines) + "\n")
    name = lines[head].split(",")[column]
    with pytest.raises(BadValueError, match=rf"far.csv data row 1, column '{name}': 1e\+308 m"):
        read_measurement_file(f, load_mechanism("wedge3"))
    res = CliRunner().invoke(main, ["calibrate", "wedge3", "--data", str(f), "--params", "patent",
                                    "--out", str(tmp_path / "cal")])  # fmt: skip
    line = _one_line(res)
    assert "more than 10 km from the origin" in line and not (tmp_path / "cal").exists()


def test_too_many_rows_refused_with_an_estimate_unless_yes(measured, tmp_path, monkeypatch):
    monkeypatch.setattr(_limits, "MAX_POSES", 50)
    args = ["calibrate", "wedge3", "--data", str(measured), "--params", "patent",
            "--out", str(tmp_path / "cal")]  # fmt: skip
    line = _one_line(CliRunner().invoke(main, args))
    assert "--data" in line and "has 60 poses, over the 50" in line
    assert " s and " in line and "GB of memory" in line and "--yes" in line
    assert not (tmp_path / "cal").exists()
    res = CliRunner().invoke(main, [*args, "--yes"])
    assert res.exit_code == 0, res.output


def test_deeply_nested_identification_json_is_one_line(tmp_path):
    d = tmp_path / "cal"
    d.mkdir()
    (d / "identification.json").write_text("[" * 100_000 + "]" * 100_000)
    res = CliRunner().invoke(main, ["acceptance", "wedge3", "--calibrated", str(d)])
    line = _one_line(res)
    assert "identification.json" in line


def test_view_live_with_stdin_closed_is_refused_before_starting():
    cmd = f"exec {sys.executable} -m pincal.cli view wedge3 --live <&-"
    proc = subprocess.run(["sh", "-c", cmd], capture_output=True, text=True, timeout=120,
                          env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"})  # fmt: skip
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr and "stdin is closed" in proc.stderr
    assert "--html FILE" in proc.stderr


def test_run_json_reports_a_failed_step_as_json(tmp_path, measured):
    camp = tmp_path / "c.yaml"
    camp.write_text(
        "model: wedge3\npreset: patent\nout: cal\nmeasurements:\n  source: file\n"
        f"  file: {tmp_path / 'bad.csv'}\nvalidation:\n  source: none\nreport: false\n"
    )
    (tmp_path / "bad.csv").write_text("# pincal measurements 1\nq0,q1\n1,2\n")
    res = CliRunner().invoke(main, ["run", str(camp), "--json"])
    assert res.exit_code == 1, res.output
    doc = json.loads(res.stdout)
    assert doc["error"]["type"] == "CampaignError"
    assert "step 'calibrate' failed" in doc["error"]["message"]


def test_live_host_not_on_this_machine_is_refused_at_once():
    """An address no interface holds fails on the first bind, not after a port scan."""
    res = CliRunner().invoke(main, ["view", "wedge3", "--random", "2", "--live",
                                    "--host", "192.0.2.1"])  # fmt: skip  (TEST-NET-1)
    line = _one_line(res)
    assert "--host 192.0.2.1 is not an address of this machine" in line and "127.0.0.1" in line
