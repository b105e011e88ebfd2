"""The identifiable set is decided on the model's measured components, not on the data's.

A planar machine measured in x, y, rz whose actual geometry is tilted (out-of-plane
errors): far from the solution, the residual Jacobian maps unmeasured rotations into the
rz row through Jlog3 of the measured deviation, which once made 35 of 78 parameters look
identifiable (second-order effects) where `pincal info` counts 21; the fit then crawled
to its iteration limit and the gate refused it.
"""

from __future__ import annotations

import json

from click.testing import CliRunner

from pincal.cli import main

RRR3 = "tests/model/machines/rrr3"


def test_info_and_calibrate_count_the_same_identifiable_set(tmp_path):
    runner = CliRunner()
    info = runner.invoke(main, ["info", RRR3, "--json"])
    assert info.exit_code == 0, info.output
    (full,) = [p for p in json.loads(info.stdout)["presets"] if p["preset"] == "full"]
    m = tmp_path / "m.csv"
    sim = runner.invoke(main, ["simulate", RRR3, "--random", "40", "--seed", "3", "--out", str(m)])
    assert sim.exit_code == 0, sim.output
    cal = runner.invoke(main, ["calibrate", RRR3, "--data", str(m), "--out", str(tmp_path / "c")])
    assert cal.exit_code == 0, cal.output[-2000:]
    assert f"identifying {full['identifiable']} of {full['parameters']} parameters" in cal.stderr
    assert "quality gate: passed" in cal.stdout
    doc = json.loads((tmp_path / "c" / "identification.json").read_text())
    assert len(doc["parameters"]) == full["identifiable"]
    assert len(doc["parameters"]) + len(doc["held"]) == full["parameters"]
