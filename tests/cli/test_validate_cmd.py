"""`pincal validate`: held-out errors, the ISO 9283 table and the Cramér–Rao prediction."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.measure import Measurements, NoiseModel, simulate_measurements
from pincal.model import load_mechanism, parameters, sample_actuators
from pincal.validation import validate_held_out


def _run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_iso9283_accuracy_and_repeatability_by_hand():
    nominal = load_mechanism("wedge3")
    params = parameters(nominal, "patent")
    actual = params.apply(nominal, np.full(len(params), 2e-4))
    rng = np.random.default_rng(0)
    q = sample_actuators(nominal, 2, rng)
    rows = q[[0, 0, 0, 1, 1]]  # two commanded poses, repeated 3 and 2 times
    meas = simulate_measurements(actual, rows, NoiseModel(0.01, 0.02), rng)
    cov = np.eye(len(params)) * 1e-12
    v = validate_held_out(nominal, actual, meas, params, params.names, cov)
    doc = v.to_dict()
    assert doc["commanded_poses"] == 2 and [r["repeats"] for r in doc["iso9283"]] == [3, 2]
    # by hand: x and z measured (wedge3 measures x z ry)
    P = meas.positions[:3][:, [0, 2]]
    cmd = nominal.forward(q[0]).translation[[0, 2]]
    assert doc["iso9283"][0]["before"]["AP_p_mm"] == pytest.approx(
        np.linalg.norm(P.mean(axis=0) - cmd) * 1e3, rel=1e-9
    )
    d = np.linalg.norm(P - P.mean(axis=0), axis=1)
    assert doc["iso9283"][0]["RP_l_mm"] == pytest.approx((d.mean() + 3 * d.std(ddof=1)) * 1e3)
    assert doc["iso9283"][0]["after"]["AP_a_mrad"] is None  # rx is not measured
    assert doc["iso9283"][0]["after"]["AP_b_mrad"] is not None
    assert doc["after"]["rms_position_mm"] < doc["before"]["rms_position_mm"] / 5
    assert doc["predicted"]["observed_rms_position_mm"] is None  # no noise given
    single = Measurements(meas.q_act[:1], meas.positions[:1], meas.rotations[:1],
                          meas.components, meas.frame, meas.actuated)  # fmt: skip
    one = validate_held_out(nominal, actual, single, params, params.names, cov).to_dict()
    assert one["iso9283"][0]["RP_l_mm"] is None


@pytest.fixture(scope="module")
def wedge_campaign(tmp_path_factory):
    d = tmp_path_factory.mktemp("wedge")
    assert _run("simulate", "wedge3", "--random", 16, "--out", d / "m.csv").exit_code == 0
    assert _run("simulate", "wedge3", "--random", 40, "--seed", 9,
                "--out", d / "held.csv").exit_code == 0  # fmt: skip
    res = _run("calibrate", "wedge3", "--data", d / "m.csv", "--out", d / "cal")
    assert res.exit_code == 0, res.output
    return d


def test_validate_json_agrees_with_the_cramer_rao_prediction(wedge_campaign):
    d = wedge_campaign
    res = _run("validate", d / "cal", "--data", d / "held.csv", "--json")
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout)
    assert doc["independent"] and doc["poses"] == 40 and doc["components"] == ["x", "z", "ry"]
    a, b, p = doc["after"], doc["before"], doc["predicted"]
    assert a["rms_position_mm"] < b["rms_position_mm"] / 5
    # achieved vs predicted (model error + instrument noise), same order of magnitude
    ratio = a["rms_position_mm"] / p["observed_rms_position_mm"]
    assert 0.5 < ratio < 2.0, ratio
    assert len(doc["per_pose"]["after_position_mm"]) == 40
    res = _run("validate", d / "cal", "--data", d / "held.csv")
    assert "ISO 9283" in res.output and "Cramér–Rao" in res.output


def test_validate_warns_on_fitting_data_and_names_missing_files(wedge_campaign, tmp_path):
    d = wedge_campaign
    res = _run("validate", d / "cal", "--data", d / "m.csv", "--json")
    assert res.exit_code == 0 and json.loads(res.stdout)["independent"] is False
    assert "used to fit" in res.stderr
    res = _run("validate", tmp_path / "nope", "--data", d / "held.csv")
    assert res.exit_code == 1 and "does not exist" in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1
