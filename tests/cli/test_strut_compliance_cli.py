"""A hexaslide whose struts yield under a 20 kg spindle: `calibrate --model
geometric+strut-compliance`, `validate` with the calibration's joint terms, `info`."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.io import (
    read_calibration,
    read_commands,
    read_measurement_file,
    write_measurements,
    write_poses,
)
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
from pincal.validation import validate_held_out

HEXASLIDE = Path(__file__).parents[2] / "models" / "hexaslide_6pus"
SPINDLE = "20,0.05,-0.02,0.1"  # kg; m in the tool frame
NOISE = {"position": 0.005, "orientation": 0.005}  # [mm], [mrad]


@pytest.fixture(scope="module")
def soft_struts(tmp_path_factory):
    """60 + 20 full poses of a hexaslide with geometric errors and soft struts."""
    mech = with_payload(load_mechanism(HEXASLIDE), Payload.parse(SPINDLE))
    params = with_joint_terms(mech, parameters(mech, "pus54"), ["strut-compliance"])
    rng = np.random.default_rng(12)
    truth = np.zeros(len(params))
    truth[: len(params) - 6] = rng.normal(0.0, 1e-4, len(params) - 6)
    truth[params.joint_terms] = -rng.uniform(3e-7, 1e-6, 6)  # [m/N]: 30–140 µm at ~140 N
    actual = params.apply(mech, truth)
    tmp = tmp_path_factory.mktemp("struts")
    for name, n in (("meas.csv", 60), ("held_out.csv", 20)):
        rows = sample_actuators(mech, n, rng)
        meas = simulate_measurements(
            actual, actual_joint_values(mech, params, truth, rows), NOISE, rng
        )
        write_measurements(tmp / name, dataclasses.replace(meas, q_act=rows))
    res = CliRunner().invoke(main, [
        "calibrate", str(HEXASLIDE), "--params", "pus54", "--data", str(tmp / "meas.csv"),
        "--model", "geometric+strut-compliance", "--payload", SPINDLE,
        "--out", str(tmp / "cal"),
    ])  # fmt: skip
    assert res.exit_code == 0, res.output
    return tmp, mech, params, truth


@pytest.mark.slow  # the fixture's fit: the loads' derivative in 54 geometric parameters
def test_struts_compliance_is_recovered(soft_struts):
    tmp, _, params, truth = soft_struts
    cal = read_calibration(tmp / "cal")
    for k in params.joint_terms:
        i = cal.result.names.index(params.names[k])
        sigma = np.sqrt(cal.result.covariance[i, i])
        assert abs(cal.result.values[i] - truth[k]) < 4 * sigma
        assert sigma < 0.1 * abs(truth[k])  # each strut determined to 10 %
    assert "strut_compliance" in (tmp / "cal" / "joint_terms.yaml").read_text()


@pytest.mark.slow  # the fixture's fit: the loads' derivative in 54 geometric parameters
def test_validate_applies_the_joint_terms(soft_struts):
    """At the noise level with the struts' compliance, visibly worse with the geometry only."""
    tmp = soft_struts[0]
    res = CliRunner().invoke(main, ["validate", str(tmp / "cal"), "--data",
                                    str(tmp / "held_out.csv"), "--json"])  # fmt: skip
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout.strip().splitlines()[-1])
    assert "6 joint terms (strut_compliance)" in doc["joint_terms"]
    noise_3d = np.sqrt(3) * NOISE["position"]  # [mm] RMS of a 3-D error of pure noise
    with_terms = doc["after"]["rms_position_mm"]
    assert with_terms < 1.3 * noise_3d
    cal = read_calibration(tmp / "cal")
    meas = read_measurement_file(tmp / "held_out.csv", cal.nominal()).measurements
    params = parameters(cal.nominal(), cal.preset)
    geometric = validate_held_out(
        cal.nominal(), cal.calibrated(), meas, params, tuple(cal.result.identified_names),
        cal.result.covariance,
    ).to_dict()["after"]["rms_position_mm"]  # fmt: skip
    print(f"held-out RMS position: {with_terms * 1e3:.2f} µm with the terms, "
          f"{geometric * 1e3:.2f} µm with the geometry only")  # fmt: skip
    assert geometric > 3 * with_terms
    empty = CliRunner().invoke(main, ["validate", str(tmp / "cal"), "--data",
                                      str(tmp / "held_out.csv"), "--payload", "0", "--json"])
    assert empty.exit_code == 0, empty.output
    empty_doc = json.loads(empty.stdout.strip().splitlines()[-1])
    assert "payload 0 kg" in empty_doc["joint_terms"]  # the load the data were not taken at
    assert empty_doc["after"]["rms_position_mm"] > 3 * with_terms
    text = CliRunner().invoke(main, ["validate", str(tmp / "cal"), "--data",
                                     str(tmp / "held_out.csv")])  # fmt: skip
    assert text.exit_code == 0 and "geometry and 6 joint terms" in text.output
    assert "geometric part only" not in text.output


@pytest.mark.slow  # the fixture's fit: the loads' derivative in 54 geometric parameters
def test_compensate_undoes_the_struts_yield(soft_struts, tmp_path):
    """Commands reach targets on the true machine, its struts' yield included."""
    tmp, mech, params, truth = soft_struts
    targets = sample_actuators(mech, 8, np.random.default_rng(3))
    poses = [mech.forward(r) for r in targets]
    write_poses(tmp_path / "targets.csv", poses, actuated=mech.actuated, q_act=targets)
    res = CliRunner().invoke(main, ["compensate", str(tmp / "cal"), "--targets",
                                    str(tmp_path / "targets.csv"), "--out",
                                    str(tmp_path / "commands.csv"), "--json"])  # fmt: skip
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout.strip().splitlines()[-1])
    assert "6 joint terms (strut_compliance)" in doc["joint_terms"]["line"]
    _, commands = read_commands(tmp_path / "commands.csv", mech)
    actual = params.apply(mech, truth)
    joints = actual_joint_values(mech, params, truth, commands)
    miss = [np.linalg.norm(actual.forward(q).translation - T.translation)
            for q, T in zip(joints, poses, strict=True)]  # fmt: skip
    largest = doc["joint_terms"]["largest_deflection"]["m"]
    print(f"RMS miss {np.sqrt(np.mean(np.square(miss))) * 1e6:.2f} µm; largest joint "
          f"change undone {largest * 1e6:.1f} µm")  # fmt: skip
    assert largest > 2e-5  # [m]: the struts' yield is tens of µm
    assert np.sqrt(np.mean(np.square(miss))) < 5e-6  # [m]: a few noise σ of the fit


def test_info_says_the_payload_and_struts_separate_only_with_changing_loads():
    args = ["info", str(HEXASLIDE), "--preset", "pus54", "--model",
            "geometric+strut-compliance", "--payload", SPINDLE, "--json"]  # fmt: skip
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout.strip().splitlines()[-1])
    assert doc["presets"][0]["identifiable"] == 54 + 6
    assert any(
        "strut-compliance" in n and "only with poses that change the load" in n and "20 kg" in n
        for n in doc["notes"]
    )
