"""Machine style: the robot.yaml collection's ``joint_type`` kinds UJOINT_XY, UJOINT_YZ,
UJOINT_ZY (two revolutes about the joint frame's first then second named axis, at the
joint origin) and FIXED (the joint locked at 0), on machines.rusr_ujoint — the RUSR of
machines.rusr_universal written that way (issue 28, cause 3)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from pincal.errors import ModelFileError, PincalError, UnknownNameError
from pincal.model import Mechanism, load_mechanism, parameters
from tests.open_world import acceptance
from tests.open_world.machines import rusr_ujoint, rusr_universal, write_machine

KINDS = ("UJOINT_XY", "UJOINT_YZ", "UJOINT_ZY")


@pytest.fixture(scope="module", params=KINDS)
def kind(request) -> str:
    return request.param


@pytest.fixture(scope="module")
def model(tmp_path_factory, kind) -> Path:
    return write_machine(tmp_path_factory.mktemp("m"), "rusr_ujoint", *rusr_ujoint(kind))


@pytest.fixture(scope="module")
def mech(model):
    return load_mechanism(model)


def test_the_named_axes_are_turned_first_then_second(mech, kind):
    """The coupler frame turns by R_a(q1)·R_b(q2) relative to the joint origin (a, b the
    named axes of the joint frame), whatever the placeholder's <axis> (1 1 0)."""
    j = mech.model.getJointId("u_joint")
    assert mech.model.joints[j].shortname() == "JointModelUniversal"
    qi = mech.model.idx_qs[j]
    q = mech.q_home.copy()
    q[qi : qi + 2] = (0.3, -0.4)
    data = mech.model.createData()
    pin.forwardKinematics(mech.model, data, q)
    relative = mech.model.jointPlacements[j].inverse() * (
        data.oMi[mech.model.parents[j]].inverse() * data.oMi[j]
    )
    a, b = kind[-2:].lower()
    expected = pin.utils.rotate(a, 0.3) @ pin.utils.rotate(b, -0.4)
    assert np.allclose(relative.rotation, expected, atol=1e-12)
    assert np.allclose(relative.translation, 0.0, atol=1e-12)
    assert f"joint 'u_joint' is a {kind} joint (sidecar joint_type)" in mech.notes


def test_same_machine_as_the_universal_one(mech):
    """Both write one RUSR: the measured coupler curve is the same to 1e-12 m."""
    ref = Mechanism(*rusr_universal())
    assert mech.mobility == 1 and mech.idle_joints == ()
    for a in np.linspace(0.2, 0.8, 7):
        d = mech.forward([a]).translation - ref.forward([a]).translation
        assert np.max(np.abs(d)) <= 1e-12


def test_fixed_joint_is_locked_at_zero(mech):
    """``mark`` (a revolute in the URDF) is locked: no Pinocchio joint, the mark frame
    at the joint origin, and the six origin parameters of a fixed joint (no offset)."""
    assert "mark" not in list(mech.model.names)
    assert mech.tree.joints["mark"].type == "fixed"
    assert "joint 'mark' is locked at 0 (sidecar joint_type FIXED)" in mech.notes
    names = [n for n in parameters(mech, "full").names if n.startswith("mark.")]
    assert names == [f"mark.{d}" for d in ("tx", "ty", "tz", "rx", "ry", "rz")]
    q = mech.configuration(np.array([0.6]))
    placement = mech.frame_placement(q, "coupler_mark")
    coupler = mech.frame_placement(q, "coupler")
    origin = mech.tree.joints["mark"].origin
    assert np.allclose((coupler * origin).homogeneous, placement.homogeneous, atol=1e-12)


def test_round_trip(mech):
    acceptance.check_round_trip(mech)


def test_jacobian_matches_central_differences(mech):
    acceptance.check_jacobian(mech)


def test_noise_free_recovery(mech):
    acceptance.check_recovery(mech)


def test_simulate_calibrate_compensate(model, tmp_path, kind):
    if kind != "UJOINT_ZY":
        pytest.skip("the CLI path is the same for every kind: run once")
    acceptance.check_cli(model, tmp_path)
    exported = next((tmp_path / "cal").glob("*.urdf")).read_text(encoding="utf-8")
    assert 'name="mark" type="fixed"' in exported  # the locked joint stays locked


def test_ujoint_zy_is_not_universal_after_z():
    """pincal's ``universal`` on a z placeholder turns about z then x: on this machine x
    of the joint frame is the coupler itself, so the coupler would spin idly and the
    machine would not be the same — the kinds must not be confused."""
    urdf, sidecar = rusr_ujoint("UJOINT_ZY")
    urdf = urdf.replace('<axis xyz="1 1 0"/>', '<axis xyz="0 0 1"/>')
    sidecar = dict(sidecar, joint_type=["universal", "FIXED"])
    try:
        other = Mechanism(urdf, sidecar)
    except PincalError:
        return  # refused: not the same machine either
    ref = Mechanism(*rusr_ujoint("UJOINT_ZY"))
    assert other.idle_joints != () or not np.allclose(
        other.forward([0.7]).translation, ref.forward([0.7]).translation, atol=1e-9
    )


def test_unknown_and_bad_kinds_are_refused():
    urdf, sidecar = rusr_ujoint("UJOINT_ZY")
    with pytest.raises(ModelFileError, match="UJOINT_ZZ|ujoint_zz.*supported kinds"):
        Mechanism(urdf, dict(sidecar, joint_type=["UJOINT_ZZ", "FIXED"]))
    with pytest.raises(UnknownNameError, match="no_such_joint"):
        Mechanism(urdf, dict(sidecar, joint_name=["u_joint", "no_such_joint"]))
