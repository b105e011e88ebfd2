"""`pincal run`'s report carries what `pincal demo`'s does; one default noise everywhere.

The campaign runs on the planar 3-RRR of tests/model/machines/rrr3 (measures x y rz), so
its validation section must also name the measured components.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.cli._campaign import Campaign
from pincal.io import read_measurement_file
from pincal.measure import DEFAULT_NOISE
from pincal.model import load_mechanism
from pincal.workflow import DemoSettings

RRR3 = Path(__file__).parents[1] / "model" / "machines" / "rrr3" / "rrr3.urdf"
CAMPAIGN = f"""\
model: {RRR3}
preset: base
design: {{count: 20, candidates: "random:120"}}
measurements: {{source: simulated}}
validation: {{source: simulated, poses: 12}}
"""


def _sections(report: Path) -> dict[str, dict]:
    return {s["title"]: s for s in json.loads(report.read_text())["sections"]}


@pytest.mark.slow  # ~35 s (a campaign run); report sections are checked fast in tests/report
def test_campaign_report_has_every_section_of_the_demo_report(tmp_path):
    (tmp_path / "c.yaml").write_text(CAMPAIGN)
    out = tmp_path / "cal"
    res = CliRunner().invoke(main, ["run", str(tmp_path / "c.yaml"), "--out", str(out)])
    assert res.exit_code == 0, res.output + res.stderr
    demo = tmp_path / "demo"
    res = CliRunner().invoke(main, ["demo", "--out", str(demo), "--poses", "24",
                                    "--validation", "12"])  # fmt: skip
    assert res.exit_code == 0, res.output + res.stderr
    camp, ref = _sections(out / "report.json"), _sections(demo / "report.json")
    assert set(ref) <= set(camp), set(ref) - set(camp)
    for title, section in ref.items():  # the same tables, with the same columns
        assert [t["headers"] for t in camp[title]["tables"]][: len(section["tables"])] == [
            t["headers"] for t in section["tables"]
        ], title
    # the validation is the one `pincal validate` computed, over x y rz
    val = json.loads((out / "validation.json").read_text())
    assert val["components"] == ["x", "y", "rz"]
    rows = {r[0]: r for r in camp["Validation"]["tables"][0]["rows"]}
    assert set(rows) == {"RMS position (x y)", "max position (x y)",
                         "RMS orientation (rz)", "max orientation (rz)"}  # fmt: skip
    assert rows["RMS orientation (rz)"][3] == round(val["after"]["rms_orientation_mrad"] * 1e3, 3)
    assert "x y rz" in camp["Validation"]["text"]
    # the simulated truth and the pose-design history, as in the demo
    params = {r[0]: r for r in camp["Identified parameters"]["tables"][0]["rows"]}
    headers = camp["Identified parameters"]["tables"][0]["headers"]
    assert "true [µm | µrad]" in headers and len(params) == 21
    md = (out / "report.md").read_text()
    assert "## Convergence and pose selection\n\n*Plots (2)" in md


def test_one_default_noise_everywhere(tmp_path):
    assert Campaign(model="x").measurements.noise == (DEFAULT_NOISE.position,
                                                      DEFAULT_NOISE.orientation)  # fmt: skip
    assert DemoSettings().noise == DEFAULT_NOISE
    shown = f"{DEFAULT_NOISE.position:g}, {DEFAULT_NOISE.orientation:g}"
    for cmd in ("poses", "simulate"):
        text = " ".join(CliRunner().invoke(main, [cmd, "--help"]).output.split())
        assert f"[default: {shown}]" in text or f"[default: {shown.replace(' ', '')}]" in text
    run_help = " ".join(CliRunner().invoke(main, ["run", "--help"]).output.split())
    assert f"noise: [{shown}]" in run_help
    res = CliRunner().invoke(main, ["simulate", str(RRR3), "--random", "3",
                                    "--out", str(tmp_path / "m.csv")])  # fmt: skip
    assert res.exit_code == 0, res.output + res.stderr
    meas = read_measurement_file(tmp_path / "m.csv", load_mechanism(str(RRR3))).measurements
    assert meas.noise == DEFAULT_NOISE
    readme = (Path(__file__).parents[2] / "README.md").read_text()
    assert f"{DEFAULT_NOISE.position:g} mm / {DEFAULT_NOISE.orientation:g} mrad" in readme
