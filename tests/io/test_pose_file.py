"""Pose files carry their actuator values (with units) and may give only some components;
command files state their units; one reader of actuator rows for viewing."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from pincal.errors import ColumnError
from pincal.io import (
    read_commands,
    read_pose_file,
    read_pose_rows,
    read_poses,
    si_actuator_units,
    write_commands,
    write_poses,
)
from pincal.model import load_mechanism, sample_actuators


@pytest.fixture(scope="module")
def wedge():
    return load_mechanism("wedge3")


def test_pose_file_round_trips_actuator_values_with_units(wedge, tmp_path):
    q = sample_actuators(wedge, 4, np.random.default_rng(2))
    poses = [wedge.forward(row) for row in q]
    path = write_poses(tmp_path / "p.csv", poses, actuated=wedge.actuated, q_act=q,
                       actuator_units=["mm"] * 3)  # fmt: skip
    text = path.read_text()
    assert "# actuated: q0 q1 q2" in text and "q0 [mm]" in text and "length_unit: mm" in text
    pf = read_pose_file(path)
    np.testing.assert_allclose(pf.q_act, q, rtol=1e-14)
    assert pf.components == ("x", "y", "z", "rx", "ry", "rz")
    np.testing.assert_allclose(read_pose_rows(path, wedge), q, rtol=1e-14)
    for a, b in zip(read_poses(path), poses, strict=True):
        np.testing.assert_allclose(a.translation, b.translation, atol=1e-12)


def test_pose_file_without_actuators_is_solved_by_inverse_kinematics(wedge, tmp_path):
    q = sample_actuators(wedge, 3, np.random.default_rng(4))
    path = write_poses(tmp_path / "p.csv", [wedge.forward(row) for row in q])
    np.testing.assert_allclose(read_pose_rows(path, wedge), q, atol=1e-9)


def test_target_file_with_only_the_controlled_components(tmp_path):
    path = tmp_path / "t.csv"
    path.write_text("# pincal poses 1\n# length_unit: mm\n# angle_unit: mrad\nx,z,ry\n10,2,-5\n")
    pf = read_pose_file(path)
    assert pf.components == ("x", "z", "ry") and pf.q_act is None
    T = pf.poses[0]
    np.testing.assert_allclose(T.translation, [0.010, 0.0, 0.002])
    np.testing.assert_allclose(pin.log3(T.rotation), [0.0, -0.005, 0.0], atol=1e-15)
    path.write_text("# pincal poses 1\n# length_unit: mm\nx,z,bogus\n1,2,3\n")
    with pytest.raises(ColumnError, match="bogus"):
        read_pose_file(path)


def test_command_file_states_units_and_reads_back(wedge, tmp_path):
    q = sample_actuators(wedge, 3, np.random.default_rng(5))
    path = write_commands(tmp_path / "c.csv", wedge.actuated, q,
                          actuator_units=si_actuator_units(wedge))  # fmt: skip
    assert "pose,q0 [m],q1 [m],q2 [m]" in path.read_text()
    idx, back = read_commands(path, wedge)
    np.testing.assert_array_equal(back, q)
    np.testing.assert_array_equal(idx, [0, 1, 2])
    np.testing.assert_array_equal(read_pose_rows(path, wedge), q)
    assert set(si_actuator_units(load_mechanism("aacmm"))) == {"rad"}
