"""Acceptance: a complete measurement campaign through the CLI, each command reading the
previous command's output as written (no renaming, no copying)."""

from __future__ import annotations

import json
import os

import pytest
from click.testing import CliRunner

from pincal.cli import main

CAMPAIGNS = {
    # model: (pose count, candidates)
    "hexaslide_6pus": (30, "random:120"),
    "wedge3": (12, "random:200"),
}


@pytest.mark.slow
@pytest.mark.parametrize("model", sorted(CAMPAIGNS))
def test_campaign_end_to_end(model, tmp_path):
    count, cands = CAMPAIGNS[model]
    runner = CliRunner()
    cwd = os.getcwd()
    os.chdir(tmp_path)

    def run(*args: str) -> dict:
        res = runner.invoke(main, [*args, "--json"])
        assert res.exit_code == 0, f"{args}\n{res.output}"
        return json.loads(res.stdout)

    try:
        p = run("poses", model, "--count", str(count), "--candidates", cands, "--out", "poses.csv")
        assert p["poses"] == "poses.csv"
        s = run("simulate", model, "--poses", "poses.csv", "--out", "m.csv")
        assert s["poses"] == count
        run("simulate", model, "--random", "15", "--seed", "7", "--out", "held_out.csv")
        c = run("calibrate", model, "--data", "m.csv", "--out", "cal")
        assert (
            c["residuals"]["after"]["rms_position_mm"] < c["residuals"]["before"]["rms_position_mm"]
        )
        v = run("view", model, "--poses", "poses.csv", "--calibrated", "cal", "--html", "v.html")
        assert v["poses"] == count and v["max_prediction_change_mm"] > 1e-3
        k = run("compensate", "cal", "--targets", "poses.csv", "--out", "commands.csv")
        assert k["commands"] == count and not k["unreachable"]
        val = run("validate", "cal", "--data", "held_out.csv")
        assert val["independent"]
        assert val["after"]["rms_position_mm"] < val["before"]["rms_position_mm"] / 5
        r = run("report", "cal")
        assert os.path.isfile(r["html"])
    finally:
        os.chdir(cwd)
    assert sorted(p.name for p in (tmp_path / "cal").iterdir() if p.is_file()) == sorted(
        ["calibrated.urdf", "calibrated.yaml", "calibration.json", "identification.json",
         "report.txt", "report.html", "report.md", "report.json"]
    )  # fmt: skip
    expected_components = {"hexaslide_6pus": 6, "wedge3": 3}[model]
    assert len(k["components"]) == expected_components
