"""Progress of long CLI steps: on stderr only, a tqdm bar on a terminal, plain lines
otherwise, and stdout stays the command's (valid ``--json``) with progress on."""

from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from pincal.cli import _progress, main


@pytest.fixture
def shown_at_once(monkeypatch):
    """Progress is shown from the first update (no delay for quick steps)."""
    monkeypatch.setattr(_progress, "DELAY", 0.0)


@pytest.fixture
def terminal(monkeypatch, shown_at_once):
    """Progress believes stderr is a terminal: tqdm bars, redrawn at every update."""
    monkeypatch.setattr(_progress, "interactive", lambda: True)
    monkeypatch.setattr(_progress, "MININTERVAL", 0.0)


def test_plain_lines_at_each_quarter_on_stderr_only(capsys, shown_at_once):
    with _progress.counted("cycles") as step:
        for k in range(1, 9):
            step(k, 8)
    out, err = capsys.readouterr()
    assert out == ""
    assert err.splitlines() == [f"… cycles: {k}/8" for k in (2, 4, 6, 8)]


def test_a_quick_counted_step_writes_nothing(capsys):
    with _progress.counted("cycles") as step:
        for k in range(1, 9):
            step(k, 8)
    assert capsys.readouterr() == ("", "")


def test_plain_iteration_lines_carry_the_cost(capsys):
    with _progress.iterations("identifying") as step:
        step(1, 12.5)
        step(2, 0.25)
    out, err = capsys.readouterr()
    assert out == ""
    assert err.splitlines() == [
        "… identifying iteration 1: cost 12.5",
        "… identifying iteration 2: cost 0.25",
    ]


def test_the_bar_goes_to_stderr_with_the_cost(capsys, terminal):
    with _progress.iterations("identifying") as step:
        step(1, 12.5)
        step(2, 0.25)
    with _progress.counted("plots", unit="plot") as step:
        step(3, 7)
    out, err = capsys.readouterr()
    assert out == ""
    assert "identifying" in err and "cost 0.25" in err and "3/7" in err


def _simulated(tmp_path):
    meas = tmp_path / "m.csv"
    args = ["simulate", "hexaslide_6pus", "--random", "14", "--errors", "seed:4",
            "--noise", "0.001,0.005", "--out", str(meas)]  # fmt: skip
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    return meas


@pytest.mark.parametrize(  # the log form (the same command, ~15 s) in the slow lane
    "bars", [True, pytest.param(False, marks=pytest.mark.slow)], ids=["terminal", "log"]
)
def test_json_stdout_stays_valid_with_progress_on(tmp_path, monkeypatch, shown_at_once, bars):
    if bars:
        monkeypatch.setattr(_progress, "interactive", lambda: True)
        monkeypatch.setattr(_progress, "MININTERVAL", 0.0)
    meas = _simulated(tmp_path)
    runner = CliRunner()
    cal = runner.invoke(
        main, ["calibrate", "hexaslide_6pus", "--data", str(meas), "--out",
               str(tmp_path / "cal"), "--json"],
    )  # fmt: skip
    assert cal.exit_code == 0, cal.output
    assert json.loads(cal.stdout)["model"] == "hexaslide_6pus"
    assert "identifying" in cal.stderr and "cost" in cal.stderr
    iso = runner.invoke(
        main, ["acceptance", "hexaslide_6pus", "--calibrated", str(tmp_path / "cal"),
               "--cycles", "4", "--json"],
    )  # fmt: skip
    assert iso.exit_code == 0, iso.output
    assert set(json.loads(iso.stdout)) >= {"before", "after"}
    assert "before: cycles" in iso.stderr and "after: cycles" in iso.stderr
    rep = runner.invoke(main, ["report", str(tmp_path / "cal"), "--json"])
    assert rep.exit_code == 0, rep.output
    assert json.loads(rep.stdout)["html"].endswith("report.html")
    assert "plots" in rep.stderr
    info = runner.invoke(main, ["info", "hexaslide_6pus", "--json"])
    assert info.exit_code == 0, info.output
    assert json.loads(info.stdout)["model"] == "hexaslide_6pus"
    assert "identifiability" in info.stderr
