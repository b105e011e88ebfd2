"""Serial chains: base/tool frames, locked joints, registration; UR10 and Panda calibration."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pincal
from pincal.errors import (
    ModelFileError,
    UnknownNameError,
)
from pincal.measure import register_instrument
from pincal.model import (
    BASE_JOINT,
    TOOL_JOINT,
    example_robot_urdf,
    lock_joints,
    serial_mechanism,
    with_joint_origin,
    wrap_base_tool,
)

ROOT = Path(__file__).resolve().parents[2]


def _load(name):
    spec = importlib.util.spec_from_file_location(name, ROOT / "scripts" / "studies" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


ur10_script = _load("ur10_calibration")

T_BASE = pin.SE3(pin.exp3(np.array([0.3, -0.1, 0.7])), np.array([2.0, 0.5, -0.3]))
T_TOOL = pin.SE3(pin.exp3(np.array([0.0, 0.2, 0.1])), np.array([0.01, -0.02, 0.15]))


def _frame(model, data, name):
    return data.oMf[model.getFrameId(name)]


def test_wrap_base_tool_composes_the_placements():
    xml = example_robot_urdf("ur10").read_text()
    wrapped = wrap_base_tool(xml, "tool0", T_BASE, T_TOOL)
    m0, m1 = pin.buildModelFromXML(xml), pin.buildModelFromXML(wrapped)
    d0, d1 = m0.createData(), m1.createData()
    q = np.random.default_rng(3).uniform(-3, 3, m0.nq)
    pin.framesForwardKinematics(m0, d0, q)
    pin.framesForwardKinematics(m1, d1, q)
    expected = T_BASE * _frame(m0, d0, "tool0") * T_TOOL
    got = _frame(m1, d1, "tool")
    assert np.allclose(got.homogeneous, expected.homogeneous, atol=1e-12)
    with pytest.raises(ModelFileError):
        wrap_base_tool(wrapped, "tool0")
    with pytest.raises(UnknownNameError):
        wrap_base_tool(xml, "no_such_link")


def test_lock_joints_follows_mimic_and_keeps_geometry():
    xml = example_robot_urdf("panda").read_text()
    locked = lock_joints(xml, {"panda_finger_joint1": 0.02})
    m0, m1 = pin.buildModelFromXML(xml), pin.buildModelFromXML(locked)
    assert m1.nq == 7 and m0.nq > 7
    q0 = pin.neutral(m0)
    for name in ("panda_finger_joint1", "panda_finger_joint2"):
        if m0.existJointName(name):
            jid = m0.getJointId(name)
            if m0.nqs[jid] == 1:
                q0[m0.idx_qs[jid]] = 0.02
    d0, d1 = m0.createData(), m1.createData()
    pin.framesForwardKinematics(m0, d0, q0)
    pin.framesForwardKinematics(m1, d1, pin.neutral(m1))
    for link in ("panda_leftfinger", "panda_rightfinger", "panda_hand_tcp"):
        assert np.allclose(_frame(m0, d0, link).homogeneous, _frame(m1, d1, link).homogeneous)
    # the fingers really moved apart by 2 × 0.02 m
    gap = (
        _frame(m1, d1, "panda_leftfinger").translation
        - _frame(m1, d1, "panda_rightfinger").translation
    )
    assert np.linalg.norm(gap) == pytest.approx(0.04, abs=1e-12)
    with pytest.raises(UnknownNameError):
        lock_joints(xml, {"panda_hand_joint": 0.0})


def test_chain_preset_counts():
    ur = serial_mechanism("ur10", "tool0")
    assert len(pincal.parameters(ur, "chain")) == 6 + 6 * 6 + 6
    assert len(pincal.parameters(ur, "base_tool")) == 12
    urp = serial_mechanism("ur10", "tool0", measured="position")
    assert len(pincal.parameters(urp, "chain")) == 6 + 6 * 6 + 3
    assert ur.measured_frame == "tool" and ur.n_actuated == 6


UR10_POSE_UNIDENTIFIABLE = {
    "shoulder_pan_joint.tx", "shoulder_pan_joint.ty", "shoulder_pan_joint.tz",
    "shoulder_pan_joint.rx", "shoulder_pan_joint.ry", "shoulder_pan_joint.offset",
    "shoulder_lift_joint.tx", "shoulder_lift_joint.rx", "elbow_joint.ty", "elbow_joint.offset",
    "wrist_1_joint.ty", "wrist_1_joint.offset", "wrist_2_joint.ty", "wrist_2_joint.ry",
    "wrist_3_joint.tz", "wrist_3_joint.rz", "tool_frame.tz", "tool_frame.rz",
}  # fmt: skip


@pytest.mark.parametrize("measured,rank", [("pose", 30), ("position", 27)])
def test_ur10_noise_free_recovery(measured, rank):
    problem = ur10_script.make_problem("ur10", 50, measured, seed=0)
    truth = problem.truth
    assert np.all(np.abs(truth[problem.identifiable]) >= 1e-4)  # 0.1–1 mm / 0.5–2 mrad
    out = ur10_script.run(problem, None)
    r = out.result
    assert len(r.params) == rank
    assert np.abs(out.parameter_error).max() <= 1e-9
    assert out.validation.position.max() < 1e-9
    if measured == "pose":
        assert set(r.fixed) == UR10_POSE_UNIDENTIFIABLE
    else:  # a point target: its orientation on the flange is invisible
        assert {"tool_frame.ty", "tool_frame.tz"} <= set(r.fixed)
    assert len(r.fixed) == len(problem.params) - rank


def test_ur10_all_errors_absorbed_by_the_base_set():
    problem = ur10_script.make_problem("ur10", 50, "pose", seed=2, all_errors=True)
    before = pincal.pose_errors(problem.nominal, problem.actual, problem.q_validation)
    out = ur10_script.run(problem, None)
    assert before.position.max() > 1e-3
    assert out.validation.position.max() < 1e-9
    assert out.validation.orientation.max() < 1e-9


def test_panda_noise_free_recovery():
    problem = ur10_script.make_problem("panda", 40, "pose", seed=1)
    out = ur10_script.run(problem, None)
    assert len(out.result.params) == 7 * 4 + 6
    assert np.abs(out.parameter_error).max() <= 1e-9


def test_registration_recovers_a_known_instrument_frame():
    nominal = serial_mechanism("ur10", "tool0", measured="position", T_flange_tool=T_TOOL)
    params = pincal.parameters(nominal, "chain")
    rng = np.random.default_rng(7)
    q_rows = pincal.sample_actuators(nominal, 50, rng)
    ident = pincal.identifiability(nominal, params, q_rows)
    truth = np.zeros(len(params))
    truth[ident.base] = ur10_script.random_errors(params, rng)[ident.base]
    actual = params.apply(with_joint_origin(nominal, BASE_JOINT, T_BASE), truth)
    meas = pincal.simulate_measurements(actual, q_rows)
    reg = register_instrument(nominal, meas)
    coarse = pin.log6(T_BASE.inverse() * reg.T_instrument_base).vector
    assert 1e-6 < np.abs(coarse).max() < 1e-2  # close, but biased by the robot's errors
    result = pincal.identify(reg.mechanism, pincal.parameters(reg.mechanism, "chain"), meas)
    base = [result.params.index(f"{BASE_JOINT}.{d}") for d in ("tx", "ty", "tz", "rx", "ry", "rz")]
    T_id = reg.T_instrument_base * pin.exp6(result.values[base])
    T_expected = T_BASE * pin.exp6(truth[:6])  # true placement incl. its base-set error
    assert np.abs(pin.log6(T_expected.inverse() * T_id).vector).max() < 1e-9
    assert result.after.max_position < 1e-9
    assert TOOL_JOINT + ".tx" in result.params.names
