"""`pincal run`: a campaign file drives the subcommands into one calibration directory."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
import yaml
from click.testing import CliRunner

import pincal.cli._campaign_steps as run_steps
from pincal.cli import main
from pincal.cli._campaign import load_campaign
from pincal.errors import CampaignError

EXAMPLE = Path(__file__).resolve().parents[2] / "docs" / "examples" / "campaign.yaml"


def _run(*args: str):
    return CliRunner().invoke(main, ["run", *args])


@pytest.mark.slow
def test_example_campaign_runs_end_to_end(tmp_path):
    out = tmp_path / "cal"
    res = _run(str(EXAMPLE), "--out", str(out), "--json")
    assert res.exit_code == 0, res.output
    summary = json.loads(res.stdout)
    status = {s["step"]: s["status"] for s in summary["steps"]}
    assert all(status[k] == "done" for k in ("design", "measure", "calibrate", "report"))
    assert status["validate"] in ("done", "skipped")
    assert summary["urdf"] == [str(out / "calibrated.urdf")]
    assert (out / "calibrated.urdf").is_file() and (out / "report.html").is_file()
    assert str(out / "report.md") in summary["report"]
    assert "pincal run: [5/7] calibrate: pincal calibrate" in res.stderr
    # the calibration recovered the seeded actual machine's errors
    doc = json.loads((out / "identification.json").read_text())
    truth = json.loads((out.parent / f"{out.name}-inputs" / "measurements.truth.json").read_text())
    true = np.array([p["value"] for p in truth["parameters"]])
    found = {p["name"]: (p["value"], p["std"]) for p in doc["parameters"]}
    names = [p["name"] for p in truth["parameters"]]
    z = [(found[n][0] - t) / found[n][1] for n, t in zip(names, true, strict=True) if n in found]
    assert len(z) > 30 and np.sqrt(np.mean(np.square(z))) < 3.0
    after = doc["residuals"]["after"]["rms_position_mm"]
    assert after < doc["residuals"]["before"]["rms_position_mm"] / 10
    # the resolved copy reruns from file measurements into its own directory
    copy = yaml.safe_load((out / "campaign.yaml").read_text())
    assert copy["out"] == "." and copy["model"] == "hexaslide_6pus"
    again = tmp_path / "again.yaml"
    copy.update(
        design=None,
        out=str(tmp_path / "again"),
        measurements={
            "source": "file",
            "file": str(out.parent / f"{out.name}-inputs" / "measurements.csv"),
        },
        validation={"source": "none"},
        identification={"method": "lm"},
        report=False,
    )
    again.write_text(yaml.safe_dump(copy))
    res = _run(str(again))
    assert res.exit_code == 0, res.output
    assert (tmp_path / "again" / "calibrated.urdf").is_file()
    assert not (tmp_path / "again-inputs").exists()
    doc2 = json.loads((tmp_path / "again" / "identification.json").read_text())
    assert doc2["method"] != doc["method"]
    v1 = np.array([p["value"] for p in doc["parameters"]])
    v2 = np.array([p["value"] for p in doc2["parameters"]])
    np.testing.assert_allclose(v2, v1, atol=1e-6)


def _campaign(tmp_path, text: str) -> Path:
    p = tmp_path / "c.yaml"
    p.write_text(text)
    return p


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("model: x\nmesurements: {}\n", "unknown key 'mesurements'; did you mean 'measurements'"),
        ("model: x\nmeasurements: {nosie: [1, 2]}\n", "did you mean 'noise'"),
        ("model: x\nmeasurements: {poses: 5, noise: [1]}\n", "measurements.noise: expected a"),
        ("model: x\nmeasurements: {poses: '5'}\n", "measurements.poses: expected int"),
        ("model: x\ndesign: {index: o1}\n", "design.index: 'o1' is not valid .*'O1'"),
        ("preset: p\n", "key 'model' is required"),
        ("model: x\nmeasurements: {poses: 5}\nvalidation: {source: file}\n", "validation.file"),
        ("model: x\n", "exactly one of a 'design' section or 'measurements.poses'"),
        (
            "model: x\nmeasurements: {source: file, file: nope.csv}\nvalidation: {source: none}\n",
            "measurements.file: .*nope.csv' does not exist",
        ),
        ("- a\n", "expected a mapping"),
        ("model: [\n", "not valid YAML"),
    ],
)
def test_campaign_file_is_checked_up_front(tmp_path, text, message):
    path = _campaign(tmp_path, text)
    with pytest.raises(CampaignError, match=message):
        load_campaign(path)
    res = _run(str(path), "--out", str(tmp_path / "out"))
    assert res.exit_code == 1 and "CampaignError" in res.output
    assert not (tmp_path / "out").exists()


def test_relative_paths_follow_the_file(tmp_path):
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "m.csv").write_text("")
    path = tmp_path / "sub" / "c.yaml"
    path.write_text(
        "model: stewart_6ups\nmeasurements: {source: file, file: m.csv}\n"
        "validation: {source: none}\n"
    )
    camp = load_campaign(path)
    assert camp.measurements.file == str(tmp_path / "sub" / "m.csv")
    assert camp.out == str(tmp_path / "sub" / "campaign-out")


def test_dry_run_and_missing_subcommand_is_skipped(tmp_path, monkeypatch):
    steps = (
        run_steps.Step("calibrate", "calibrate", run_steps._calibrate),
        run_steps.Step("future", "no-such-command", lambda c, p: [str(p.out), "--x"]),
    )
    monkeypatch.setattr(run_steps, "STEPS", steps)
    path = _campaign(tmp_path, "model: stewart_6ups\nmeasurements: {poses: 30}\n")
    out = tmp_path / "out"
    res = _run(str(path), "--out", str(out), "--dry-run", "--json")
    assert res.exit_code == 0, res.output
    summary = json.loads(res.stdout)
    assert [s["status"] for s in summary["steps"]] == ["planned", "skipped"]
    note = summary["steps"][1]["note"]
    assert "no `no-such-command` command" in note and f"{out} --x" in note
    assert "[1/2] calibrate: pincal calibrate stewart_6ups --data" in res.stderr
    assert not out.exists()


def test_a_failing_step_stops_the_run(tmp_path):
    bad = tmp_path / "m.csv"
    bad.write_text("# pincal measurements 1\n# frame: platform\nleg1\n")
    path = _campaign(
        tmp_path,
        f"model: stewart_6ups\nmeasurements: {{source: file, file: {bad}}}\n"
        "validation: {source: none}\n",
    )
    res = _run(str(path), "--out", str(tmp_path / "out"))
    assert res.exit_code == 1
    assert "step 'calibrate' failed" in res.output
    assert "report" not in res.output.split("failed")[-1]


def test_every_key_is_documented_and_the_example_is_valid():
    import dataclasses

    from pincal.cli import _campaign

    def keys(cls):
        for f in dataclasses.fields(cls):
            yield f.name
            sub = getattr(_campaign, f.name.capitalize(), None)
            if f.name == "measurements":
                sub = _campaign.MeasurementSource
            if sub is not None and dataclasses.is_dataclass(sub):
                yield from keys(sub)

    for key in keys(_campaign.Campaign):
        assert re.search(rf"\n +{key}:", _campaign.KEYS_HELP), key
    camp = load_campaign(EXAMPLE)
    assert camp.model == "hexaslide_6pus" and camp.design is not None
    res = CliRunner().invoke(main, ["run", "--help"])
    assert res.exit_code == 0 and "errors_seed: 0" in res.output and "Examples:" in res.output


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--bogus"], r"step 'x': `pincal simulate` rejected the arguments .*--bogus"),
        (["stewart_6ups", "--out", "m.csv"], r"step 'x' \(`pincal simulate`\): give exactly one"),
    ],
)
def test_a_step_usage_error_is_a_campaign_error(tmp_path, monkeypatch, args, message):
    monkeypatch.setattr(run_steps, "STEPS", (run_steps.Step("x", "simulate", lambda c, p: args),))
    path = _campaign(tmp_path, "model: stewart_6ups\nmeasurements: {poses: 30}\n")
    res = _run(str(path), "--out", str(tmp_path / "out"))
    assert res.exit_code == 1, res.output
    assert re.search(f"CampaignError: {message}", res.output), res.output


@pytest.mark.slow
def test_tracker_example_imports_and_calibrates(tmp_path):
    import shutil

    shutil.copytree(EXAMPLE.parent / "tracker", tmp_path / "tracker")
    d = tmp_path / "tracker"
    res = CliRunner().invoke(main, [
        "import-tracker", str(d / "points.csv"), "--log", str(d / "controller_log.csv"),
        "--targets", str(d / "targets_local.csv"), "--model", "hexaslide_6pus",
        "--point-std", "0.005", "--out", str(d / "targets.csv")])  # fmt: skip
    assert res.exit_code == 0, res.output
    res = _run(str(d / "campaign.yaml"), "--json")
    assert res.exit_code == 0, res.output
    out = d / "hexaslide-tracker-cal"
    assert json.loads(res.stdout)["urdf"] == [str(out / "calibrated.urdf")]
    assert (out / "report.html").is_file()
    doc = json.loads((out / "identification.json").read_text())
    assert doc["poses"] == 16 and 0.3 < doc["reduced_chi2"] < 3.0
    r = doc["residuals"]
    assert r["after"]["rms_position_mm"] < r["before"]["rms_position_mm"] / 50
