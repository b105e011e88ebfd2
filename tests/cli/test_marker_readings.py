"""Marker tables in other people's habits, from the CLI: mapped joints, degrees, a reference.

A simulated UR5 seen by a capture system, written as a lab would export it: a frame
counter, joint columns ``q1``…``q6`` in degrees *relative to the robot's home pose*,
mapped to the URDF joints by a local sidecar (``robot: ur5``), marker positions in mm,
a marker copied under other names, and rows where the camera lost a marker (empty or
``nan`` cells). The truth is known: a wrong unit, mapping or reference would move the
calibrated marker by centimetres at unseen poses.
"""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
from click.testing import CliRunner

from pincal.cli import main
from pincal.identification import is_registration
from pincal.measure import MarkerSetup, marker_mechanism
from pincal.model import BASE_JOINT, TOOL_JOINT, parameters, sample_actuators, with_joint_origin

T_TRUE = pin.SE3(pin.rpy.rpyToMatrix(-0.1, 0.15, 2.1), np.array([0.9, 1.1, -0.2]))
MARKER = np.array([0.04, -0.03, 0.09])
SIDECAR = """robot: ur5
columns: {q1: shoulder_pan_joint, q2: shoulder_lift_joint, q3: elbow_joint,
          q4: wrist_1_joint, q5: wrist_2_joint, q6: wrist_3_joint}
joint_reference: home
"""


def _run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def _actual():
    mech = marker_mechanism("ur5", MarkerSetup("wrist_3_link"))
    actual = with_joint_origin(mech, BASE_JOINT, T_TRUE)
    actual = with_joint_origin(actual, TOOL_JOINT, pin.SE3(np.eye(3), MARKER))
    params = parameters(actual, "chain")
    x = np.random.default_rng(3).uniform(-1e-3, 1e-3, len(params))
    return mech, params.apply(actual, np.where([is_registration(n) for n in params.names], 0, x))


def _points(mech, q):
    return np.array([mech.frame_placement(c).translation for c in mech.configurations(q)])


def _export(path, mech, actual, q, header: str = "") -> None:
    """frame, x1..z1, x2..z2 (a copy of marker 1) [mm], q1..q6 [deg from home]."""
    P = _points(actual, q) + np.random.default_rng(4).normal(0, 2e-5, (len(q), 3))
    rel = np.degrees(q - mech.actuators_of(mech.q_home))
    lines = ["frame,x1,y1,z1,x2,y2,z2,q1,q2,q3,q4,q5,q6"]
    for i in range(len(q)):
        mk = [f"{v:.6f}" for v in P[i] * 1e3]
        if i == 4:
            mk[1] = ""  # marker lost by the cameras
        if i == 9:
            mk[2] = "NaN"
        lines.append(",".join([str(i), *mk, *mk, *(f"{v:.8f}" for v in rel[i])]))
    path.write_text(header + "\n".join(lines) + "\n")


def _check_truth(cal_dir, mech, actual):
    from pincal.io import read_calibration

    cal = read_calibration(cal_dir).calibrated()
    q_new = sample_actuators(mech, 20, np.random.default_rng(8))
    err = np.linalg.norm(_points(cal, q_new) - _points(actual, q_new), axis=1)
    assert np.sqrt(np.mean(err**2)) < 2e-4, err.max()


def test_mapped_columns_degrees_and_home_reference_from_the_sidecar(tmp_path):
    mech, actual = _actual()
    q = sample_actuators(mech, 30, np.random.default_rng(1))
    _export(tmp_path / "mocap.csv", mech, actual, q)
    (tmp_path / "ur5_lab.yaml").write_text(SIDECAR + "joint_units: deg\n")
    r = _run("calibrate", tmp_path / "ur5_lab.yaml", "--link", "wrist_3_link",
             "--data", tmp_path / "mocap.csv", "--marker-columns", "x1,y1,z1;x2,y2,z2",
             "--length-unit", "mm", "--out", tmp_path / "cal", "--json")  # fmt: skip
    assert r.exit_code == 0, r.output
    assert "2 of 30 rows left out, a marker used not seen" in r.stderr
    assert "lines 6, 11" in r.stderr  # file lines (title on line 1)
    doc = json.loads(r.stdout.splitlines()[-1])["markers"]
    assert any("repeat x1,y1,z1" in n for n in doc["notes"])
    assert any("rows left out" in n for n in doc["notes"])
    _check_truth(tmp_path / "cal", mech, actual)
    # the cross-validation rebuilds the same rows from the recorded data file
    v = _run("validate", tmp_path / "cal", "--cv", "3", "--json")
    assert v.exit_code == 0, v.output
    cv = json.loads(v.stdout)["cv"]
    assert cv["poses"] == 28
    assert cv["held_out_rms_mm"] < 0.2 < cv["baseline"]["held_out_rms_mm"]


def test_the_file_header_declares_the_unit(tmp_path):
    """``# joint_units: deg`` before the title line: without it, degrees read as radians."""
    mech, actual = _actual()
    q = sample_actuators(mech, 25, np.random.default_rng(2))
    (tmp_path / "ur5_lab.yaml").write_text(SIDECAR)
    _export(tmp_path / "bare.csv", mech, actual, q)
    args = [tmp_path / "ur5_lab.yaml", "--link", "wrist_3_link", "--marker-columns", "x1,y1,z1",
            "--length-unit", "mm"]  # fmt: skip
    bad = _run("calibrate", *args, "--data", tmp_path / "bare.csv", "--out", tmp_path / "c0")
    assert bad.exit_code != 0
    assert "degrees read as radians" in bad.output or "outside" in bad.output, bad.output
    assert not (tmp_path / "c0").exists()
    _export(tmp_path / "decl.csv", mech, actual, q, header="# joint_units: deg\n")
    r = _run("calibrate", *args, "--data", tmp_path / "decl.csv", "--out", tmp_path / "cal")
    assert r.exit_code == 0, r.output
    _check_truth(tmp_path / "cal", mech, actual)


def test_a_missing_joint_reading_is_named(tmp_path):
    mech, actual = _actual()
    q = sample_actuators(mech, 10, np.random.default_rng(2))
    (tmp_path / "ur5_lab.yaml").write_text(SIDECAR + "joint_units: deg\n")
    _export(tmp_path / "m.csv", mech, actual, q)
    text = (tmp_path / "m.csv").read_text().splitlines()
    cells = text[3].split(",")
    cells[-1] = ""
    text[3] = ",".join(cells)
    (tmp_path / "m.csv").write_text("\n".join(text) + "\n")
    r = _run("calibrate", tmp_path / "ur5_lab.yaml", "--link", "wrist_3_link",
             "--data", tmp_path / "m.csv", "--marker-columns", "x1,y1,z1",
             "--length-unit", "mm", "--out", tmp_path / "cal")  # fmt: skip
    assert r.exit_code != 0
    assert "line 4" in r.output and "'q6'" in r.output, r.output


def test_a_campaign_locks_a_joint_the_file_does_not_have(tmp_path):
    """``markers.lock``: wrist 1 stood still at -1.2 rad and was not exported."""
    mech, actual = _actual()
    q = sample_actuators(mech, 30, np.random.default_rng(6))
    q[:, 3] = -1.2
    _export(tmp_path / "full.csv", mech, actual, q)
    lines = (tmp_path / "full.csv").read_text().splitlines()
    k = lines[0].split(",").index("q4")
    (tmp_path / "mocap.csv").write_text(
        "".join(",".join(c for j, c in enumerate(ln.split(",")) if j != k) + "\n" for ln in lines)
    )
    (tmp_path / "ur5_lab.yaml").write_text(SIDECAR + "joint_units: deg\n")
    (tmp_path / "campaign.yaml").write_text(
        "model: ur5_lab.yaml\nmeasurements: {source: file, file: mocap.csv}\n"
        "markers:\n  link: wrist_3_link\n  columns: [x1, y1, z1]\n  length_unit: mm\n"
        "  lock: {wrist_1_joint: -1.2}\n"
        "validation: {source: none, cv: 3}\nreport: false\n"
    )
    r = _run("run", tmp_path / "campaign.yaml", "--out", tmp_path / "cal")
    assert r.exit_code == 0, r.output
    assert "--lock wrist_1_joint=-1.2" in r.stderr
    cv = json.loads((tmp_path / "cal" / "validation.json").read_text())["cv"]
    assert cv["held_out_rms_mm"] < 0.2
    _check_truth_at(tmp_path / "cal", actual, -1.2)
    # the locked value is the campaign's: a wrong one leaves centimetres
    (tmp_path / "bad.yaml").write_text(
        (tmp_path / "campaign.yaml").read_text().replace("-1.2}", "0.0}")
    )
    bad = _run("run", tmp_path / "bad.yaml", "--out", tmp_path / "cal2", "--force")
    assert "the registration leaves" in bad.output, bad.output


def _check_truth_at(cal_dir, actual, wrist_1: float):
    from pincal.io import read_calibration

    cal = read_calibration(cal_dir).calibrated()
    q_new = sample_actuators(cal, 20, np.random.default_rng(8))
    q_full = np.insert(q_new, 3, wrist_1, axis=1)
    err = np.linalg.norm(_points(cal, q_new) - _points(actual, q_full), axis=1)
    assert np.sqrt(np.mean(err**2)) < 2e-4, err.max()


def test_a_table_without_titles_is_named(tmp_path):
    mech, actual = _actual()
    q = sample_actuators(mech, 5, np.random.default_rng(2))
    _export(tmp_path / "m.csv", mech, actual, q)
    lines = (tmp_path / "m.csv").read_text().splitlines()
    (tmp_path / "m.csv").write_text("\n".join(lines[1:]) + "\n")
    r = _run("calibrate", "ur5", "--link", "wrist_3_link", "--data", tmp_path / "m.csv",
             "--marker-columns", "x1,y1,z1", "--out", tmp_path / "cal")  # fmt: skip
    assert r.exit_code != 0
    assert "the first line holds numbers, not column titles" in r.output, r.output


def test_the_solver_line_names_why_lm_ran():
    from pincal.report._marker_text import solver_line

    assert solver_line("lm", "gauss-newton", "huber") == (
        "solver: lm (the huber loss runs Levenberg–Marquardt)"
    )
    assert solver_line("lm", "gauss-newton", "linear") == "solver: lm (switched from gauss-newton)"
    assert solver_line("lm", "lm", "huber") is None
