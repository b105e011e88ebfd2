"""The batched numpy kinematics reproduces Pinocchio pose by pose (1e-12)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import pincal
from pincal.model.batch._batch import BatchModel

MODELS = ["stewart_6ups", "hexaslide_6pus", "pkm5", "wedge3", "aacmm", "ur10"]


def _random_configurations(model: pin.Model, n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    q0 = pin.neutral(model)
    return np.array([pin.integrate(model, q0, rng.standard_normal(model.nv)) for _ in range(n)])


@pytest.fixture(scope="module", params=MODELS)
def mech(request):
    return pincal.load_mechanism(request.param)


def _spherical_model() -> pin.Model:
    model = pin.Model()
    j1 = model.addJoint(0, pin.JointModelRUBZ(), pin.SE3.Random(), "a")
    j2 = model.addJoint(j1, pin.JointModelSpherical(), pin.SE3.Random(), "b")
    j3 = model.addJoint(j2, pin.JointModelFreeFlyer(), pin.SE3.Random(), "c")
    j4 = model.addJoint(j3, pin.JointModelPY(), pin.SE3.Random(), "d")
    model.addFrame(pin.Frame("tip", j4, 0, pin.SE3.Random(), pin.FrameType.OP_FRAME))
    return model


def _check(model: pin.Model, Q: np.ndarray) -> None:
    bm = BatchModel(model)
    assert bm.supported
    bk = bm.kinematics(Q)
    data = model.createData()
    for i, q in enumerate(Q):
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        np.testing.assert_allclose(bk.jacobian[i], data.J, atol=1e-12)
        for j in range(model.njoints):
            np.testing.assert_allclose(bk.rotations[i, j], data.oMi[j].rotation, atol=1e-12)
            np.testing.assert_allclose(bk.translations[i, j], data.oMi[j].translation, atol=1e-12)
    for fid in range(model.nframes):
        R, p = bm.frame_placement(bk, fid)
        J = bm.frame_jacobian(bk, fid)
        Jlwa = bm.frame_jacobian(bk, fid, local_world_aligned=True)
        for i, q in enumerate(Q):
            pin.computeJointJacobians(model, data, q)
            pin.updateFramePlacements(model, data)
            np.testing.assert_allclose(R[i], data.oMf[fid].rotation, atol=1e-12)
            np.testing.assert_allclose(p[i], data.oMf[fid].translation, atol=1e-12)
            np.testing.assert_allclose(
                J[i], pin.getFrameJacobian(model, data, fid, pin.LOCAL), atol=1e-12
            )
            np.testing.assert_allclose(
                Jlwa[i],
                pin.getFrameJacobian(model, data, fid, pin.LOCAL_WORLD_ALIGNED),
                atol=1e-12,
            )


def test_kinematics_matches_pinocchio(mech):
    _check(mech.model, _random_configurations(mech.model, 5, 1))


def test_spherical_free_flyer_unbounded_match_pinocchio():
    model = _spherical_model()
    _check(model, _random_configurations(model, 5, 2))


@pytest.mark.parametrize("scale", [1.0, 1e-6, 0.0])
def test_integrate_matches_pinocchio(mech, scale):
    model = mech.model
    Q = _random_configurations(model, 4, 3)
    DV = scale * np.random.default_rng(4).standard_normal((4, model.nv))
    out = BatchModel(model).integrate(Q, DV)
    for i in range(4):
        ref = pin.integrate(model, Q[i], DV[i])
        assert np.max(np.abs(pin.difference(model, ref, out[i]))) < 1e-12


def test_integrate_spherical_matches_pinocchio():
    model = _spherical_model()
    Q = _random_configurations(model, 4, 5)
    DV = np.random.default_rng(6).standard_normal((4, model.nv))
    out = BatchModel(model).integrate(Q, DV)
    for i in range(4):
        ref = pin.integrate(model, Q[i], DV[i])
        assert np.max(np.abs(pin.difference(model, ref, out[i]))) < 1e-12


def test_unsupported_joint_is_reported():
    # (planar joints are supported since: tests/model/test_batch_joint_kinds.py)
    model = pin.Model()
    model.addJoint(0, pin.JointModelTranslation(), pin.SE3.Identity(), "translation")
    assert not BatchModel(model).supported
