"""Robots loaded by name through the CLI: defaults, --frame/--lock/--sidecar, `robot:` key,
PAL mimic joints, a local directory shadowing a name, joint columns named and scaled."""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from pincal._files import read_text
from pincal.cli import main
from pincal.model import UrdfTree, example_robot_urdf, load_mechanism, srdf_home

ARM = [f"arm_{i}_joint" for i in range(1, 8)]


def run(args: list[str]):
    return CliRunner().invoke(main, args)


def info_json(*args: str) -> dict:
    res = run(["info", *args, "--preset", "full", "--json"])
    assert res.exit_code == 0, res.output
    return json.loads(res.stdout.strip().splitlines()[-1])


def test_panda_fingers_are_not_actuated_and_home_is_the_srdf_state():
    doc = info_json("panda")
    assert doc["mobility"] == 7
    assert doc["actuated"] == [f"panda_joint{i}" for i in range(1, 8)]
    notes = " ".join(doc["notes"])
    assert "panda_finger_joint1, panda_finger_joint2" in notes
    assert "not actuated for calibration" in notes
    assert "state 'default' of panda.srdf" in notes
    mech = load_mechanism("panda")
    q = mech.actuators_of(mech.q_home)
    assert q[3] == pytest.approx(-2.35619) and q[5] == pytest.approx(1.5707)


def test_ur5_joints_over_one_turn_are_sampled_over_one_turn():
    res = run(["info", "ur5"])
    assert res.exit_code == 0, res.output
    assert "sampled over one turn around home" in res.output
    mech = load_mechanism("ur5")
    lo, hi = np.array([mech.workspace.joints[j] for j in mech.actuated if j != "elbow_joint"]).T
    assert np.allclose(hi - lo, 2 * math.pi)
    assert mech.actuator_limits[0, 1] == pytest.approx(2 * math.pi)  # URDF limits kept


def test_a_singular_home_is_said_and_a_sidecar_home_removes_it(tmp_path):
    # a sidecar home wins over the searched one, even a singular one (wrist_2_joint = 0)
    side = tmp_path / "ur5_cell.yaml"
    side.write_text("robot: ur5\nhome: {shoulder_lift_joint: -1.2, elbow_joint: 1.5}\n")
    res = run(["poses", str(side), "--count", "8", "--out", str(tmp_path / "p.csv")])
    assert res.exit_code == 0, res.output
    assert "pincal: note: home is a singular configuration" in res.stderr
    assert "--sidecar FILE" in res.stderr
    res = run(["info", str(side)])
    assert res.exit_code == 0 and "home is a singular configuration" in res.output
    side.write_text(
        "robot: ur5\nhome: {shoulder_lift_joint: -1.2, elbow_joint: 1.5, wrist_2_joint: -1.5}\n"
    )
    res = run(["info", str(side)])
    assert res.exit_code == 0, res.output
    assert "home is a singular" not in res.output


def test_tiago_needs_a_frame_and_takes_it_with_locks():
    res = run(["info", "tiago"])
    assert res.exit_code == 1
    assert "cannot choose the measured frame" in res.output and "--frame" in res.output
    doc = info_json("tiago", "--frame", "arm_7_link", "--lock", "torso_lift_joint=0.2")
    assert doc["measured_frame"] == "arm_7_link"
    assert doc["actuated"] == ARM and doc["mobility"] == 7
    assert any("locked: torso_lift_joint = 0.2" in n for n in doc["notes"])


def test_tiago_by_a_local_sidecar_file_and_directory(tmp_path):
    text = "robot: tiago\nmeasured_frame: arm_7_link\nlock: {torso_lift_joint: 0.15}\n"
    (tmp_path / "my_tiago.yaml").write_text(text)
    doc = info_json(str(tmp_path / "my_tiago.yaml"))
    assert doc["actuated"] == ARM and doc["measured_frame"] == "arm_7_link"
    folder = tmp_path / "cell"
    folder.mkdir()
    (folder / "cell.yaml").write_text(text)
    assert info_json(str(folder))["actuated"] == ARM
    # the same file beside the robot's name; the CLI's --lock wins over the file's
    side = str(tmp_path / "my_tiago.yaml")
    doc = info_json("tiago", "--sidecar", side, "--lock", "arm_1_joint=0")
    assert doc["actuated"] == ARM[1:]
    # a sidecar for another robot is refused
    res = run(["info", "panda", "--sidecar", str(tmp_path / "my_tiago.yaml")])
    assert res.exit_code == 1 and "describes robot 'tiago'" in res.output
    (tmp_path / "norobot.yaml").write_text("measured_frame: arm_7_link\n")
    res = run(["info", str(tmp_path / "norobot.yaml")])
    assert res.exit_code == 1 and "robot: ur5" in res.output


def test_bad_lock_option_is_a_usage_error():
    res = run(["info", "tiago", "--frame", "arm_7_link", "--lock", "torso_lift_joint"])
    assert res.exit_code == 2 and "JOINT=VALUE" in res.output
    res = run(["info", "tiago", "--frame", "arm_7_link", "--lock", "no_such_joint=0"])
    assert res.exit_code == 1 and "no_such_joint" in res.output


def test_talos_lock_skips_mimic_on_fixed_joints():
    # talos' gripper has <mimic> on fixed joints (gripper_left_inner_double_joint …)
    args = ["talos_reduced", "--frame", "gripper_left_base_link"]
    locks = ["--lock", "gripper_left_joint=0,torso_1_joint=0", "--lock", "torso_2_joint=home"]
    doc = info_json(*args, *locks)
    assert doc["actuated"] == [f"arm_left_{i}_joint" for i in range(1, 8)]
    assert any("state 'half_sitting' of talos.srdf" in n for n in doc["notes"])
    urdf = example_robot_urdf("talos_reduced")
    home = srdf_home(urdf, UrdfTree(read_text(urdf, "URDF")))[0]["torso_2_joint"]
    assert home != 0 and any(f"torso_2_joint = {home:.6g}" in n for n in doc["notes"])


def test_local_directory_shadowing_a_robot_name_is_said(tmp_path, monkeypatch):
    (tmp_path / "ur5").mkdir()
    shutil.copy(example_robot_urdf("panda"), tmp_path / "ur5" / "ur5.urdf")
    monkeypatch.chdir(tmp_path)
    res = run(["info", "ur5"])
    assert res.exit_code == 0, res.output
    assert "is the local path ./ur5" in res.output
    assert "not the example-robot-data robot 'ur5'" in res.output
    res = run(["poses", "ur5", "--count", "8", "--out", "p.csv"])
    assert res.exit_code == 0, res.output
    assert "pincal: note: model 'ur5' is the local path" in res.stderr
    monkeypatch.chdir(tmp_path / "ur5")
    res = run(["info", "ur5"])
    assert res.exit_code == 0 and "is the local path" not in res.output


def _renamed_in_degrees(src: Path, dst: Path, reference: dict[str, float]) -> None:
    """The file with joints renamed J1…J6, in degrees, relative to ``reference``."""
    lines = src.read_text().splitlines()
    k = next(i for i, line in enumerate(lines) if not line.startswith("#"))
    cols = lines[k].split(",")
    names = {c: f"J{i + 1}" for i, c in enumerate(cols[:6])}
    out = [*lines[:k], ",".join(names.get(c, c) for c in cols)]
    for line in lines[k + 1 :]:
        v = line.split(",")
        pairs = zip(cols[:6], v[:6], strict=True)
        joints = [math.degrees(float(x) - reference[c]) for c, x in pairs]
        out.append(",".join([repr(x) for x in joints] + v[6:]))
    dst.write_text("\n".join(out) + "\n")


def _values(stdout: str) -> np.ndarray:
    doc = json.loads(stdout.strip().splitlines()[-1])
    return np.array([p["value"] for p in doc["parameters"]])


def test_joint_columns_renamed_in_degrees_relative_to_home(tmp_path):
    res = run(["simulate", "ur5", "--random", "25", "--out", str(tmp_path / "m.csv")])
    assert res.exit_code == 0, res.output
    mech = load_mechanism("ur5")
    home = dict(zip(mech.actuated, mech.actuators_of(mech.q_home), strict=True))
    _renamed_in_degrees(tmp_path / "m.csv", tmp_path / "renamed.csv", home)
    side = tmp_path / "ur5_cell.yaml"
    cols = ", ".join(f"J{i + 1}: {j}" for i, j in enumerate(mech.actuated))
    side.write_text(f"columns: {{{cols}}}\njoint_units: {{angle: deg}}\njoint_reference: home\n")
    outs = {}
    for label, data, extra in (
        ("plain", "m.csv", []),
        ("renamed", "renamed.csv", ["--sidecar", str(side)]),
    ):
        args = ["calibrate", "ur5", "--data", str(tmp_path / data), "--params", "base"]
        res = run([*args, "--out", str(tmp_path / label), "--json", *extra])
        assert res.exit_code == 0, res.output
        outs[label] = _values(res.stdout)
    a, b = outs["plain"], outs["renamed"]
    assert np.allclose(a, b, rtol=1e-6, atol=1e-9)
    assert (tmp_path / "renamed" / "model.yaml").is_file()  # the options, for later commands
    res = run(["validate", str(tmp_path / "renamed"), "--data", str(tmp_path / "renamed.csv")])
    assert res.exit_code == 0, res.output
    # the same declarations in the file header instead of the sidecar
    text = (tmp_path / "renamed.csv").read_text().splitlines()
    header = [f"# columns: {' '.join(f'J{i + 1}={j}' for i, j in enumerate(mech.actuated))}",
              "# joint_units: angle=deg", "# joint_reference: home"]  # fmt: skip
    (tmp_path / "h.csv").write_text("\n".join(text[:1] + header + text[1:]) + "\n")
    args = ["calibrate", "ur5", "--data", str(tmp_path / "h.csv"), "--params", "base"]
    res = run([*args, "--out", str(tmp_path / "h"), "--json"])
    assert res.exit_code == 0, res.output
    assert np.allclose(_values(res.stdout), a, rtol=1e-6, atol=1e-9)


def test_degrees_read_as_radians_are_refused_naming_column_and_row(tmp_path):
    res = run(["simulate", "ur5", "--random", "6", "--out", str(tmp_path / "m.csv")])
    assert res.exit_code == 0, res.output
    zero = dict.fromkeys(load_mechanism("ur5").actuated, 0.0)
    _renamed_in_degrees(tmp_path / "m.csv", tmp_path / "deg.csv", zero)
    side = tmp_path / "s.yaml"
    cols = ", ".join(f"J{i + 1}: {j}" for i, j in enumerate(zero))
    side.write_text(f"columns: {{{cols}}}\n")  # no unit declared: SI (rad)
    args = ["calibrate", "ur5", "--data", str(tmp_path / "deg.csv"), "--sidecar", str(side)]
    res = run([*args, "--out", str(tmp_path / "c")])
    assert res.exit_code == 1
    assert "ActuatorRangeError" in res.output and "check the column's unit" in res.output
    assert "data row" in res.output and "column 'J" in res.output


def test_view_takes_the_model_options(tmp_path):
    html = tmp_path / "v.html"
    args = ["view", "tiago", "--frame", "arm_tool_link", "--lock", "torso_lift_joint=0.3"]
    res = run([*args, "--html", str(html), "--json"])
    assert res.exit_code == 0, res.output
    assert html.is_file() and json.loads(res.stdout)["poses"] == 5
