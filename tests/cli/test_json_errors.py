"""With ``--json`` an error is one JSON object on stdout: ``{"error": {type, message}}``.

Every subcommand that has ``--json`` is driven into an error (a pincal error, a usage
error caught while parsing, a usage error raised by the command): stdout must parse as
that object, name what was wrong, and the exit code must be non-zero.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from pincal.cli import main

ROOT = Path(__file__).resolve().parents[2]

CASES = [
    # (argv, exit code, error type, words the message must hold)
    (["info", "wedge3", "--preset", "nope", "--json"], 1, "UnknownNameError", "presets are"),
    (["poses", "wedge3", "--count", "abc", "--json"], 2, "BadParameter", "--count"),
    (["simulate", "wedge3", "--random", "3", "--out", "/dev/null", "--json"], 1,
     "OutputPathError", "--out /dev/null"),
    (["calibrate", "wedge3", "--data", "{tmp}/none.csv", "--out", "{tmp}/cal", "--json"], 1,
     "MeasurementFileError", "none.csv"),
    (["compensate", "{tmp}/nocal", "--targets", "{tmp}/t.csv", "--out", "{tmp}/c.csv",
      "--json"], 1, "", "nocal"),
    (["validate", "{tmp}/nocal", "--data", "{tmp}/t.csv", "--json"], 1, "", "nocal"),
    (["view", "wedge3", "--random", "2", "--html", "/dev/null", "--json"], 1,
     "OutputPathError", "--html"),
    (["report", "{tmp}/nocal", "--json"], 1, "", "nocal"),
    (["import-tracker", "{tmp}/none.csv", "--log", "{tmp}/t.csv", "--targets", "{tmp}/t.csv",
      "--model", "wedge3", "--out", "{tmp}/o.csv", "--json"], 2, "BadParameter", "none.csv"),
    (["acceptance", "wedge3", "--cycles", "1", "--json"], 2, "BadParameter", "--cycles"),
    (["demo", "--out", "/dev/null", "--json"], 1, "", "/dev/null"),
    (["run", "{tmp}/t.csv", "--json"], 1, "CampaignError", "t.csv"),
]  # fmt: skip


@pytest.mark.parametrize("argv, code, kind, words", CASES, ids=[c[0][0] for c in CASES])
def test_json_error_object_on_stdout(tmp_path, argv, code, kind, words):
    (tmp_path / "t.csv").write_text("x,y\n1,2\n")
    args = [a.format(tmp=tmp_path) for a in argv]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == code, res.output
    doc = json.loads(res.stdout)
    assert set(doc) == {"error"} and set(doc["error"]) == {"type", "message"}, doc
    assert not kind or doc["error"]["type"] == kind, doc
    assert words in doc["error"]["message"], doc
    assert "Traceback" not in res.output


def test_without_json_the_error_stays_one_line_on_stderr(tmp_path):
    res = CliRunner().invoke(main, ["simulate", "wedge3", "--random", "3", "--out", "/dev/null"])
    assert res.exit_code == 1 and res.stdout == ""
    assert res.stderr.startswith("pincal: error: OutputPathError: --out /dev/null")
    assert res.stderr.count("\n") == 1


def test_closed_stdout_pipe_exits_0_silently(tmp_path):
    """``pincal … | head``: the output is written; the closed pipe is not an error."""
    data = tmp_path / "m.csv"
    run = [sys.executable, "-m", "pincal.cli"]
    env = {"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"}
    subprocess.run([*run, "simulate", "wedge3", "--random", "40", "--out", str(data)],
                   check=True, capture_output=True, env=env)  # fmt: skip
    proc = subprocess.Popen(
        [*run, "calibrate", "wedge3", "--data", str(data), "--params", "patent",
         "--out", str(tmp_path / "cal")],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env,
    )  # fmt: skip
    assert proc.stdout is not None and proc.stderr is not None
    proc.stdout.readline()
    proc.stdout.close()  # as `head -1` does
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=300) == 0, err
    assert "BrokenPipe" not in err and "error" not in err.lower(), err
    assert (tmp_path / "cal" / "calibration.json").is_file()
