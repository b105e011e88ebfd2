"""The Pinocchio model models/wedge3 realises the patent's wedge mechanism exactly.

Uses Pinocchio directly (no pincal engine): the loops are closed by a small Newton
iteration on the passive joints, then the measured frame is compared with the
closed form of pincal.machines._wedge.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml

from pincal.machines import (
    WedgeGeometry,
    wedge_constraints,
    wedge_forward,
    wedge_inverse,
    wedge_urdf,
)

MODEL_DIR = Path(__file__).resolve().parents[2] / "models" / "wedge3"
PASSIVE = ("z_guide", "bar_rev", "wedge1_slide", "wedge2_slide")
ACTUATED = ("q0", "q1", "q2")
PAIRS = (("wedge1_shoe", "bar_end1"), ("wedge2_shoe", "bar_end2"))


def _closure_residual_and_jacobian(model: pin.Model, data: pin.Data, q: np.ndarray):
    pin.forwardKinematics(model, data, q)
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    res, jac = [], []
    for a, b in PAIRS:
        ia, ib = model.getFrameId(a), model.getFrameId(b)
        oMa, oMb = data.oMf[ia], data.oMf[ib]
        # closure components [x, z] = R_aᵀ (p_b − p_a); Newton on the world difference
        res.append((oMb.translation - oMa.translation)[[0, 2]])
        Ja = pin.getFrameJacobian(model, data, ia, pin.LOCAL_WORLD_ALIGNED)[:3]
        Jb = pin.getFrameJacobian(model, data, ib, pin.LOCAL_WORLD_ALIGNED)[:3]
        jac.append((Jb - Ja)[[0, 2]])
        # the out-of-plane component must vanish identically (planar mechanism)
        assert abs(oMb.translation[1] - oMa.translation[1]) < 1e-15
    return np.concatenate(res), np.vstack(jac)


def _close_loops(model: pin.Model, q_act: np.ndarray) -> np.ndarray:
    """Configuration with the given motor positions and closed loops (Newton, 1e-14 m)."""
    q = pin.neutral(model)
    for name, value in zip(ACTUATED, q_act, strict=True):
        q[model.joints[model.getJointId(name)].idx_q] = value
    idx = [model.joints[model.getJointId(n)].idx_v for n in PASSIVE]
    for _ in range(30):
        r, J = _closure_residual_and_jacobian(model, pin.Data(model), q)
        if np.linalg.norm(r) < 1e-14:
            return q
        dv = np.zeros(model.nv)
        dv[idx] = -np.linalg.solve(J[:, idx], r)
        q = pin.integrate(model, q, dv)
    raise AssertionError(f"loops did not close, residual {np.linalg.norm(r)}")


def _measured(model: pin.Model, q: np.ndarray, frame: str = "bar_centre") -> np.ndarray:
    """Measured components [x, z, ry] of the measured frame."""
    data = pin.Data(model)
    pin.framesForwardKinematics(model, data, q)
    oMf = data.oMf[model.getFrameId(frame)]
    ry = pin.log3(oMf.rotation)
    assert abs(ry[0]) < 1e-15 and abs(ry[2]) < 1e-15
    return np.array([oMf.translation[0], oMf.translation[2], ry[1]])


def _patent_pose(model: pin.Model, q_act: np.ndarray) -> np.ndarray:
    q = _close_loops(model, q_act)
    x, z, ry = _measured(model, q)
    return np.array([x, z, -ry])  # the patent's α is minus the rotation about +y


def test_model_file_is_the_generated_nominal_urdf() -> None:
    text = (MODEL_DIR / "wedge3.urdf").read_text()
    assert text == wedge_urdf(WedgeGeometry.nominal())


def test_sidecar_names_exist() -> None:
    model = pin.buildModelFromUrdf(str(MODEL_DIR / "wedge3.urdf"))
    side = yaml.safe_load((MODEL_DIR / "wedge3.yaml").read_text())
    frames = {f.name for f in model.frames}
    joints = set(model.names)
    for a, b in side["closed_loop"]:
        assert a in frames and b in frames
    assert side["type"] == [["x", "z"], ["x", "z"]]
    assert set(side["name_mot"]) == set(ACTUATED) <= joints
    assert side["measured_frame"] in frames
    assert side["measured"] == ["x", "z", "ry"]
    for entry in side["presets"]["patent"]:
        assert entry["joints"] in joints or entry["joints"] in frames
    # the nominal model closes at q = 0
    r, _ = _closure_residual_and_jacobian(model, model.createData(), pin.neutral(model))
    assert np.linalg.norm(r) == 0.0


@pytest.mark.parametrize(
    "geom",
    [
        WedgeGeometry.nominal(),
        WedgeGeometry(l1=0.1, l2=0.12, k1=0.18, k2=0.27, dq0=1.3e-3, dq1=-2.1e-3, dq2=0.7e-3),
    ],
)
def test_closed_pose_satisfies_patent_equations(geom: WedgeGeometry) -> None:
    model = pin.buildModelFromXML(wedge_urdf(geom))
    rng = np.random.default_rng(4)
    poses = rng.uniform([-0.05, -0.002, -0.01], [0.05, 0.002, 0.01], size=(20, 3))
    for q_act in wedge_inverse(poses, geom):
        pose = _patent_pose(model, q_act)
        np.testing.assert_allclose(wedge_constraints(q_act, pose, geom), 0.0, atol=1e-12)
        np.testing.assert_allclose(pose, wedge_forward(q_act, geom), atol=1e-12)


def _perturb_joint(model: pin.Model, joint: str, twist: np.ndarray) -> None:
    jid = model.getJointId(joint)
    model.jointPlacements[jid] = model.jointPlacements[jid] * pin.exp6(pin.Motion(twist))


def _perturb_frame(model: pin.Model, frame: str, twist: np.ndarray) -> None:
    fid = model.getFrameId(frame)
    model.frames[fid].placement = model.frames[fid].placement * pin.exp6(pin.Motion(twist))


def test_patent_preset_mapping() -> None:
    """Perturbing the nominal model along the `patent` preset dofs reproduces the
    patent's parameters with the mapping documented in models/wedge3/README.md."""
    nom = WedgeGeometry.nominal()
    model = pin.buildModelFromUrdf(str(MODEL_DIR / "wedge3.urdf"))
    off = {"q0": 0.8e-3, "q1": -1.1e-3, "q2": 0.5e-3}  # q*.offset [m]
    tx1, tx2 = 0.9e-3, -1.4e-3  # bar_end1/2 tx [m]
    ry1, ry2 = 0.02, -0.03  # wedge1/2_slide ry [rad]
    for j, v in off.items():
        _perturb_joint(model, j, np.array([v, 0, 0, 0, 0, 0]))
    _perturb_frame(model, "bar_end1", np.array([tx1, 0, 0, 0, 0, 0]))
    _perturb_frame(model, "bar_end2", np.array([tx2, 0, 0, 0, 0, 0]))
    _perturb_joint(model, "wedge1_slide", np.array([0, 0, 0, 0, ry1, 0]))
    _perturb_joint(model, "wedge2_slide", np.array([0, 0, 0, 0, ry2, 0]))
    dl1, dl2 = -tx1, tx2
    geom = WedgeGeometry(
        l1=nom.l1 + dl1,
        l2=nom.l2 + dl2,
        k1=np.tan(np.arctan(nom.k1) + ry1),
        k2=np.tan(np.arctan(nom.k2) - ry2),
        dq0=off["q0"],
        dq1=off["q1"] + dl1,
        dq2=off["q2"] - dl2,
    )
    rng = np.random.default_rng(5)
    for q_act in rng.uniform(-0.01, 0.01, size=(10, 3)):
        np.testing.assert_allclose(
            _patent_pose(model, q_act), wedge_forward(q_act, geom), atol=1e-12
        )
