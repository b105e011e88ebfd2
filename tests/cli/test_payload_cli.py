"""`calibrate --payload` and `compensate` with joint terms: a Stewart platform whose legs
yield under a 20 kg spindle, calibrated and compensated from the command line."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
import yaml
from click.testing import CliRunner

from pincal.cli import main
from pincal.io import read_commands, write_measurements, write_poses
from pincal.measure import simulate_measurements
from pincal.model import (
    Payload,
    actual_joint_values,
    load_mechanism,
    parameters,
    sample_actuators,
    with_joint_terms,
    with_payload,
)

STEWART = Path(__file__).parents[2] / "models" / "stewart_6ups"
SPINDLE = "20,0.05,-0.02,0.1"  # kg; m in the tool frame


@pytest.fixture(scope="module")
def sagging_stewart(tmp_path_factory):
    """80 full poses of a Stewart platform with geometric errors and soft legs."""
    mech = with_payload(load_mechanism(STEWART), Payload.parse(SPINDLE))
    params = with_joint_terms(mech, parameters(mech, "stewart42"), ["compliance"])
    rng = np.random.default_rng(8)
    truth = np.zeros(len(params))
    truth[: len(params) - 6] = rng.normal(0.0, 1e-4, len(params) - 6)
    truth[params.joint_terms] = -rng.uniform(5e-6, 2e-5, 6)  # legs shorten: 0.2–1 mm
    rows = sample_actuators(mech, 80, rng)
    actual = params.apply(mech, truth)
    meas = simulate_measurements(
        actual, actual_joint_values(mech, params, truth, rows), {"position": 0.005,
        "orientation": 0.005}, rng,
    )  # fmt: skip
    tmp = tmp_path_factory.mktemp("sag")
    write_measurements(tmp / "meas.csv", dataclasses.replace(meas, q_act=rows))
    targets = sample_actuators(mech, 10, rng)
    poses = [mech.forward(r) for r in targets]
    write_poses(tmp / "targets.csv", poses, actuated=mech.actuated, q_act=targets)
    return tmp, mech, params, truth, poses


def _miss(mech, params, truth, commands, poses) -> float:
    """RMS position error [m] of the true machine driven with ``commands``."""
    actual = params.apply(mech, truth)
    joints = actual_joint_values(mech, params, truth, commands)
    e = [np.linalg.norm(actual.forward(q).translation - T.translation)
         for q, T in zip(joints, poses, strict=True)]  # fmt: skip
    return float(np.sqrt(np.mean(np.square(e))))


@pytest.mark.slow
def test_compliance_calibration_compensates_the_sag(sagging_stewart):
    tmp, mech, params, truth, poses = sagging_stewart
    runner = CliRunner()
    misses = {}
    for model in ("geometric", "geometric+compliance"):
        cal = tmp / model
        args = ["calibrate", str(STEWART), "--data", str(tmp / "meas.csv"), "--model", model,
                "--payload", SPINDLE, "--out", str(cal)]  # fmt: skip
        res = runner.invoke(main, args)
        assert res.exit_code == 0 or model == "geometric", res.output
        if res.exit_code != 0:  # the gate may refuse the misfit geometric model: force it
            res = runner.invoke(main, [*args, "--force"])
            assert res.exit_code == 0, res.output
        out = tmp / f"{model}.csv"
        res = runner.invoke(main, ["compensate", str(cal), "--targets", str(tmp / "targets.csv"),
                                   "--out", str(out), "--json"])  # fmt: skip
        assert res.exit_code == 0, res.output
        doc = json.loads(res.stdout.strip().splitlines()[-1])
        _, commands = read_commands(out, mech)
        misses[model] = _miss(mech, params, truth, commands, poses)
        if model == "geometric":
            assert doc["joint_terms"] is None
            continue
        record = yaml.safe_load((cal / "joint_terms.yaml").read_text())
        assert record["payload"]["mass_kg"] == 20.0
        assert {t["unit"] for t in record["terms"]} == {"m/N"} and len(record["terms"]) == 6
        assert "6 joint terms (compliance)" in doc["joint_terms"]["line"]
        assert doc["joint_terms"]["largest_deflection"]["m"] > 1e-4  # [m] the sag undone
        res = runner.invoke(main, ["compensate", str(cal), "--targets", str(tmp / "targets.csv"),
                                   "--out", str(tmp / "empty.csv"), "--payload", "0",
                                   "--json"])  # fmt: skip
        assert res.exit_code == 0, res.output
        empty = json.loads(res.stdout.strip().splitlines()[-1])["joint_terms"]
        assert "payload 0 kg" in empty["line"]  # the platform alone: a smaller sag
        loaded = doc["joint_terms"]["largest_deflection"]["m"]
        assert empty["largest_deflection"]["m"] < 0.3 * loaded
        assert "m/N" in (cal / "report.txt").read_text()
        res = runner.invoke(main, ["report", str(cal), "--out", str(tmp / "rep"), "--json"])
        assert res.exit_code == 0, res.output
        md = (tmp / "rep" / "report.md").read_text()
        row = next(line for line in md.splitlines() if "leg2_slide.compliance" in line)
        assert "m/N" in row and "e-0" in row, row  # SI with its unit, not scaled as µm
    print(f"RMS miss [µm]: { ({k: round(v * 1e6, 2) for k, v in misses.items()}) }")
    assert misses["geometric+compliance"] < 0.2 * misses["geometric"], misses
    assert misses["geometric+compliance"] < 20e-6, misses  # [m]


def test_payload_needs_a_compliance_calibration(tmp_path):
    """--payload on a model or a geometric calibration is refused, naming the fix."""
    runner = CliRunner()
    (tmp_path / "t.csv").write_text("x,y,z\n0,0,0\n")
    res = runner.invoke(main, ["compensate", "ur5", "--targets", str(tmp_path / "t.csv"),
                               "--out", str(tmp_path / "c.csv"), "--payload", "5"])  # fmt: skip
    assert res.exit_code != 0 and "compliance" in res.output
    res = runner.invoke(main, ["calibrate", "ur5", "--data", str(tmp_path / "m.csv"),
                               "--payload", "5,0,0", "--out", str(tmp_path / "cal")])  # fmt: skip
    assert res.exit_code != 0 and "MASS,X,Y,Z" in res.output


def test_info_says_payload_and_compliance_separate_only_with_changing_loads():
    args = ["info", str(STEWART), "--preset", "stewart42", "--model", "geometric+compliance",
            "--payload", SPINDLE, "--json"]  # fmt: skip
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout.strip().splitlines()[-1])
    assert doc["presets"][0]["identifiable"] == 42 + 6  # every leg's compliance
    assert any("only with poses that change the load" in n and "20 kg" in n for n in doc["notes"])


def test_select_model_finds_the_sag(sagging_stewart):
    """Held-out error: the legs' compliance pays on a platform carrying a spindle."""
    tmp = sagging_stewart[0]
    args = ["select-model", str(STEWART), "--data", str(tmp / "meas.csv"), "--models",
            "geometric,geometric+compliance", "--payload", SPINDLE, "--json"]  # fmt: skip
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout.strip().splitlines()[-1])
    assert doc["recommended"] == "geometric+compliance", doc


@pytest.mark.parametrize(
    ("payload", "says"),
    [("20,100000,0,0", "centre of mass"), ("1e9", "mass"), ("20,0,0,-11", "centre of mass")],
)
def test_payload_mass_and_centre_are_bounded(tmp_path, payload, says):
    """A 100 km lever arm or a million-tonne mass is a typing slip (issue 38, item 9):
    refused as a usage error naming the bound, before the data are read."""
    res = CliRunner().invoke(main, ["calibrate", "stewart_6ups", "--data",
                                    str(tmp_path / "m.csv"), "--model",
                                    "geometric+compliance", "--payload", payload,
                                    "--out", str(tmp_path / "cal")])  # fmt: skip
    assert res.exit_code == 2, res.output
    said = " ".join(res.output.split())
    assert "--payload" in said and says in said and "at most" in said, said


def _edited(cal, tmp, old: str, new: str):
    """A copy of ``cal`` whose joint_terms.yaml reads ``new`` for ``old``, re-hashed."""
    import hashlib
    import shutil

    copy = tmp / f"edited-{abs(hash(new))}"
    shutil.copytree(cal, copy)
    record = copy / "joint_terms.yaml"
    text = record.read_text()
    assert old in text
    record.write_text(text.replace(old, new, 1))
    manifest = json.loads((copy / "calibration.json").read_text())
    manifest["files"]["joint_terms.yaml"] = hashlib.sha256(record.read_bytes()).hexdigest()
    (copy / "calibration.json").write_text(json.dumps(manifest, indent=1))
    return copy


def test_the_terms_record_agrees_with_what_is_applied(sagging_stewart):
    """joint_terms.yaml (what a reader sees) against identification.json's values and the
    nominal model's payload (what is applied): an edited, re-hashed record is refused
    (issue 38, item 9); before, it was ignored silently."""
    tmp = sagging_stewart[0]
    cal = tmp / "record"
    res = CliRunner().invoke(main, ["calibrate", str(STEWART), "--data", str(tmp / "meas.csv"),
                                    "--model", "geometric+compliance", "--payload", SPINDLE,
                                    "--out", str(cal)])  # fmt: skip
    assert res.exit_code == 0, res.output
    args = ["--targets", str(tmp / "targets.csv"), "--out", str(tmp / "c.csv")]
    res = CliRunner().invoke(main, ["compensate", str(cal), *args])
    assert res.exit_code == 0, res.output
    record = yaml.safe_load((cal / "joint_terms.yaml").read_text())
    mass = record["payload"]["mass_kg"]
    value = record["terms"][0]["value"]
    for old, new, says in (
        (f"mass_kg: {mass}", f"mass_kg: {mass * 2}", "payload"),
        (f"value: {value}", f"value: {value * 3}", record["terms"][0]["name"]),
    ):
        res = CliRunner().invoke(main, ["compensate", str(_edited(cal, tmp, old, new)), *args])
        assert res.exit_code == 1, res.output
        assert "CalibrationDirectoryError" in res.output and says in res.output, res.output
