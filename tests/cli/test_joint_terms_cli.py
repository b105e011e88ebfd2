"""`calibrate --model geometric+…`, `info --model`, the campaign key: joint terms on the CLI."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.cli._campaign import load_campaign
from pincal.errors import CampaignError
from pincal.io import write_measurements
from pincal.measure import simulate_measurements
from pincal.model import (
    actual_joint_values,
    load_mechanism,
    parameters,
    sample_actuators,
    with_joint_terms,
)

TRUTH = {"shoulder_lift_joint.compliance": 2e-5, "elbow_joint.compliance": -1e-5}  # rad/(N·m)


@pytest.fixture(scope="module")
def compliant_ur5_data(tmp_path_factory):
    """60 full poses of a UR5 whose shoulder and elbow bend under gravity."""
    mech = load_mechanism("ur5")
    params = with_joint_terms(mech, parameters(mech, ["elbow_joint.offset"]), ["compliance"])
    truth = np.zeros(len(params))
    for name, v in TRUTH.items():
        truth[params.index(name)] = v
    rng = np.random.default_rng(5)
    rows = sample_actuators(mech, 60, rng)
    meas = simulate_measurements(
        mech,
        actual_joint_values(mech, params, truth, rows),
        {"position": 0.01, "orientation": 0.01},
        rng,
    )
    path = tmp_path_factory.mktemp("jt") / "ur5.csv"
    write_measurements(path, dataclasses.replace(meas, q_act=rows))
    return path


def test_calibrate_recovers_compliance(compliant_ur5_data, tmp_path):
    runner = CliRunner()
    out = tmp_path / "cal"
    res = runner.invoke(main, ["calibrate", "ur5", "--data", str(compliant_ur5_data),
                               "--params", "base", "--model", "geometric+compliance",
                               "--out", str(out), "--json"])  # fmt: skip
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout.strip().splitlines()[-1])
    got = {p["name"]: p for p in doc["parameters"]}
    for name, v in TRUTH.items():
        assert got[name]["unit"] == "rad/(N·m)"
        assert abs(got[name]["value"] - v) < 4 * got[name]["std"], got[name]
        assert got[name]["std"] < 0.05 * abs(v)  # really identified, not a loose band
    assert "shoulder_pan_joint.compliance" not in got  # no gravity torque about a vertical axis
    report = (out / "report.txt").read_text()
    assert "rad/(N·m)" in report


def test_geometric_only_leaves_a_residual(compliant_ur5_data, tmp_path):
    """The same data without the compliance terms: the fit is visibly worse."""
    runner = CliRunner()
    fits = {}
    for model in ("geometric", "geometric+compliance"):
        res = runner.invoke(main, ["calibrate", "ur5", "--data", str(compliant_ur5_data),
                                   "--params", "base", "--model", model, "--force",
                                   "--out", str(tmp_path / model), "--json"])  # fmt: skip
        assert res.exit_code == 0, res.output
        doc = json.loads(res.stdout.strip().splitlines()[-1])
        fits[model] = doc["residuals"]["after"]["rms_position_mm"]
    assert fits["geometric+compliance"] < 0.02  # the noise level (0.01 mm per component)
    assert fits["geometric"] > 2 * fits["geometric+compliance"]


@pytest.mark.parametrize(
    ("spec", "words"),
    [("compliance", "must read 'geometric'"), ("geometric+backlash", "unknown error-model term")],
)
def test_bad_model_is_one_line(compliant_ur5_data, tmp_path, spec, words):
    res = CliRunner().invoke(main, ["calibrate", "ur5", "--data", str(compliant_ur5_data),
                                    "--model", spec, "--out", str(tmp_path / "c")])  # fmt: skip
    assert res.exit_code != 0
    assert words in res.output
    assert "Traceback" not in res.output


def test_info_lists_terms_and_says_what_is_unseen():
    res = CliRunner().invoke(main, ["info", "ur5", "--preset", "base", "--model",
                                    "geometric+compliance+gain"])  # fmt: skip
    assert res.exit_code == 0, res.output
    assert "preset 'base': 42 parameters, 39 identifiable" in res.output
    assert "shoulder_pan_joint.compliance is not identifiable" in res.output


def test_campaign_key(tmp_path):
    f = tmp_path / "c.yaml"
    f.write_text("model: ur5\nmeasurements: {poses: 10}\nidentification: {model: geometric+gain}\n")
    assert load_campaign(f).identification.model == "geometric+gain"
    f.write_text("model: ur5\nmeasurements: {poses: 10}\nidentification: {model: gain}\n")
    with pytest.raises(CampaignError, match="identification.model"):
        load_campaign(f)


def test_validate_cv_refuses_joint_terms(compliant_ur5_data, tmp_path):
    """validate --cv predicts with the URDF (no joint terms): it refuses, naming select-model;
    validate --data predicts with the terms and says so."""
    runner = CliRunner()
    out = tmp_path / "cal"
    res = runner.invoke(main, ["calibrate", "ur5", "--data", str(compliant_ur5_data),
                               "--params", "base", "--model", "geometric+compliance",
                               "--out", str(out)])  # fmt: skip
    assert res.exit_code == 0, res.output
    res = runner.invoke(main, ["validate", str(out), "--cv", "3"])
    assert res.exit_code != 0
    assert "select-model" in res.output and "Traceback" not in res.output
    res = runner.invoke(main, ["validate", str(out), "--data", str(compliant_ur5_data)])
    assert res.exit_code == 0, res.output
    assert "calibrated model: geometry and 6 joint terms (compliance)" in res.output  # applied
    assert "geometric part only" not in res.output
