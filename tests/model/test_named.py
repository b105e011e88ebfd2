"""Robots by name: SRDF home, locks through PAL mimic joints, local sidecars."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pytest

from pincal._files import read_text
from pincal.errors import ModelFileError
from pincal.model import (
    Mechanism,
    UrdfTree,
    example_robot_urdf,
    find_local_sidecar,
    load_mechanism,
    lock_joints,
    model_record,
    serial_mechanism,
    srdf_home,
)


def test_srdf_home_of_panda_talos_and_none_for_ur5():
    panda = example_robot_urdf("panda")
    home, where = srdf_home(panda, UrdfTree(read_text(panda, "URDF")))
    assert where == "state 'default' of panda.srdf"
    assert home["panda_joint4"] == pytest.approx(-2.35619)
    talos = example_robot_urdf("talos_reduced")
    home, where = srdf_home(talos, UrdfTree(read_text(talos, "URDF")))
    assert "half_sitting" in where and "arm_left_4_joint" in home
    ur5 = example_robot_urdf("ur5")
    assert srdf_home(ur5, UrdfTree(read_text(ur5, "URDF"))) is None


def test_lock_joints_through_mimic_on_fixed_joints_of_talos():
    xml = read_text(example_robot_urdf("talos_reduced"), "URDF")
    root = ET.fromstring(xml)
    def fixed_mimic(r: ET.Element) -> list[ET.Element]:
        joints = r.findall("joint")
        return [e for e in joints if e.get("type") == "fixed" and e.find("mimic") is not None]

    assert len(fixed_mimic(root)) == 12  # what made lock_joints crash
    locked = lock_joints(xml, {"gripper_left_joint": -0.3, "gripper_right_joint": 0.0})
    assert not fixed_mimic(ET.fromstring(locked))
    frame = {"measured_frame": "gripper_left_motor_double_link"}
    before, after_m = Mechanism(xml, frame), Mechanism(locked, frame)
    q = before.q_home.copy()
    moved = before.frame_placement(q).homogeneous
    q[before.model.idx_qs[before.model.getJointId("gripper_left_joint")]] = -0.3
    want = before.frame_placement(q).homogeneous
    got = after_m.frame_placement(after_m.q_home).homogeneous
    assert np.allclose(got, want, atol=1e-12) and not np.allclose(got, moved, atol=1e-3)


def test_local_sidecar_needs_robot_and_record_reloads(tmp_path):
    text = "robot: ur5\nmeasured_frame: tool0\nlock: {wrist_3_joint: 0.5}\n"
    (tmp_path / "a.yaml").write_text(text)
    assert find_local_sidecar(tmp_path / "a.yaml") == tmp_path / "a.yaml"
    mech = load_mechanism(tmp_path / "a.yaml")
    assert mech.measured_frame == "tool0" and "wrist_3_joint" not in mech.actuated
    rec = model_record(str(tmp_path / "a.yaml"), frame="wrist_3_link")
    assert rec["robot"] == "ur5" and rec["lock"] == {"wrist_3_joint": 0.5}
    assert rec["measured_frame"] == "wrist_3_link"
    (tmp_path / "b.yaml").write_text("robot: ur5\nlock: {wrist_3_joint: big}\n")
    with pytest.raises(ModelFileError, match="must be a finite number"):
        load_mechanism(tmp_path / "b.yaml")


def test_serial_mechanism_takes_a_local_sidecar_with_locks(tmp_path):
    (tmp_path / "t.yaml").write_text("robot: tiago\nlock: {torso_lift_joint: 0.2}\n")
    mech = serial_mechanism(str(tmp_path / "t.yaml"), "arm_7_link", measured="position")
    assert mech.measured_frame == "tool"
    assert list(mech.actuated) == [f"arm_{i}_joint" for i in range(1, 8)]
    assert not mech.tree.joints["torso_lift_joint"].movable


def test_a_robot_name_in_a_sidecar_is_not_a_local_path(tmp_path, monkeypatch):
    # the natural layout: ./ur5/ur5.yaml says `robot: ur5` (the example-robot-data arm)
    (tmp_path / "ur5").mkdir()
    (tmp_path / "ur5" / "ur5.yaml").write_text("robot: ur5\nmeasured_frame: tool0\n")
    monkeypatch.chdir(tmp_path)
    mech = load_mechanism("ur5")
    assert mech.measured_frame == "tool0" and mech.source == example_robot_urdf("ur5")
    assert not any("local path" in n for n in mech.notes)
    assert model_record("ur5", frame="wrist_3_link")["robot"] == "ur5"


@pytest.mark.parametrize(
    ("robot", "srdf", "state"),
    [("panda", "panda.srdf", "default"), ("talos_reduced", "talos.srdf", "half_sitting")],
)
def test_srdf_home_agrees_with_pinocchio_reference_configurations(robot, srdf, state):
    import pinocchio as pin

    urdf = example_robot_urdf(robot)
    model = pin.buildModelFromUrdf(str(urdf))
    pin.loadReferenceConfigurations(model, str(urdf.parents[1] / "srdf" / srdf), False)
    q = model.referenceConfigurations[state]
    home, where = srdf_home(urdf, UrdfTree(read_text(urdf, "URDF")))
    assert where == f"state {state!r} of {srdf}" and len(home) >= 7
    for joint, value in home.items():
        assert q[model.idx_qs[model.getJointId(joint)]] == value, joint


def test_a_sidecar_workspace_replaces_the_one_turn_default(tmp_path):
    default = load_mechanism("ur5")
    assert len(default.workspace.joints) == 5  # elbow_joint's URDF range is one turn
    (tmp_path / "w.yaml").write_text(
        "robot: ur5\nworkspace: {joints: {shoulder_pan_joint: [-1.0, 1.0]}}\n"
    )
    mech = load_mechanism(tmp_path / "w.yaml")
    assert mech.workspace.joints == {"shoulder_pan_joint": (-1.0, 1.0)}
    assert not any("one turn" in n for n in mech.notes)
