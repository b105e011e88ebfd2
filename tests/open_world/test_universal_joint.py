"""Machine style: a universal joint from the sidecar (``joint_type: universal``), on a
hand-written spatial RUSR four-bar (machines.rusr_universal)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from pincal.errors import ModelFileError, UnreachablePoseError
from pincal.model import Mechanism, load_mechanism
from tests.open_world import acceptance
from tests.open_world.machines import rusr_universal, write_machine


@pytest.fixture(scope="module")
def model(tmp_path_factory) -> Path:
    return write_machine(tmp_path_factory.mktemp("m"), "rusr", *rusr_universal())


@pytest.fixture(scope="module")
def mech(model):
    return load_mechanism(model)


def test_loads_with_a_universal_joint(mech):
    j = mech.model.getJointId("u_joint")
    joint = mech.model.joints[j]
    assert joint.shortname() == "JointModelUniversal" and joint.nq == joint.nv == 2
    # the U joint fixes the coupler spin: square passive closure Jacobian, no idle dof
    assert mech.mobility == 1 and mech.idle_joints == () and mech.home_branch != 0.0
    assert "joint 'u_joint' is a universal joint (sidecar joint_type)" in mech.notes


def test_axes_follow_the_documented_rule(mech):
    """First axis: the placeholder's <axis> (z); second: x. The coupler frame turns by
    Rz(q1)·Rx(q2) relative to the joint origin."""
    j = mech.model.getJointId("u_joint")
    qi = mech.model.idx_qs[j]
    q = mech.q_home.copy()
    q[qi : qi + 2] = (0.3, -0.4)
    data = mech.model.createData()
    pin.forwardKinematics(mech.model, data, q)
    relative = data.oMi[mech.model.parents[j]].inverse() * data.oMi[j]
    expected = pin.utils.rotate("z", 0.3) @ pin.utils.rotate("x", -0.4)
    assert np.allclose(relative.rotation, expected, atol=1e-12)
    assert np.allclose(relative.translation, [0.05, 0, 0], atol=1e-12)


def test_a_universal_placeholder_must_be_revolute():
    urdf, sidecar = rusr_universal()
    prismatic = urdf.replace(
        '<joint name="u_joint" type="revolute">', '<joint name="u_joint" type="prismatic">'
    )
    assert prismatic != urdf
    with pytest.raises(ModelFileError, match="placeholder must be a revolute joint"):
        Mechanism(prismatic, sidecar)


def test_round_trip(mech):
    acceptance.check_round_trip(mech)


def test_jacobian_matches_central_differences(mech):
    acceptance.check_jacobian(mech)


def test_noise_free_recovery(mech):
    acceptance.check_recovery(mech)


def test_simulate_calibrate_compensate(model, tmp_path):
    acceptance.check_cli(model, tmp_path)


def test_unreachable_target_from_a_regular_home_names_no_dead_point(mech):
    far = pin.SE3(np.eye(3), np.array([1.0, 1.0, 1.0]))
    with pytest.raises(UnreachablePoseError, match="unreachable") as info:
        mech.inverse(far)
    assert "dead point" not in str(info.value)
