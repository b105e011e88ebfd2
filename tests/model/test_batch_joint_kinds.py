"""Batched kinematics of universal and planar joints equals Pinocchio (1e-12).

Random trees mixing ``JointModelUniversal`` (unit axes, perpendicular or not) and
``JointModelPlanar`` with revolute, unbounded revolute, prismatic, spherical and
free-flyer joints: placements, the WORLD joint Jacobian, frame Jacobians and
``integrate`` against Pinocchio on 50 random configurations; then two machines run the
batched path end to end: the sidecar's universal joint on the spatial RUSR four-bar and
a planar 3-RPR whose platform is a URDF planar joint.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pincal
from pincal.model import COMPONENTS
from pincal.model.batch._batch import BatchModel
from pincal.sensitivity import pose_sensitivity
from tests.open_world.machines import rusr_universal, write_machine

TOL = 1e-12


def _unit(rng: np.random.Generator) -> np.ndarray:
    v = rng.standard_normal(3)
    return v / np.linalg.norm(v)


def _universal(rng: np.random.Generator, perpendicular: bool) -> pin.JointModel:
    a, b = _unit(rng), _unit(rng)
    if perpendicular:
        b -= (b @ a) * a
        b /= np.linalg.norm(b)
    return pin.JointModelUniversal(a, b)


def _random_tree(seed: int) -> pin.Model:
    """A random tree: universal and planar joints at several depths, on one another and
    under / over revolute, spherical and free-flyer joints, with random placements."""
    rng = np.random.default_rng(seed)
    model = pin.Model()

    def add(parent: int, joint: pin.JointModel, name: str) -> int:
        return model.addJoint(parent, joint, pin.SE3.Random(), name)

    u1 = add(0, _universal(rng, True), "u1")
    u2 = add(0, _universal(rng, False), "u2")  # same depth and kind as u1: one group
    pl1 = add(0, pin.JointModelPlanar(), "pl1")
    r1 = add(u1, pin.JointModelRevoluteUnaligned(_unit(rng)), "r1")
    u3 = add(u2, _universal(rng, False), "u3")
    s1 = add(pl1, pin.JointModelSpherical(), "s1")
    pl2 = add(u1, pin.JointModelPlanar(), "pl2")
    pl3 = add(r1, pin.JointModelPlanar(), "pl3")
    u4 = add(pl3, _universal(rng, True), "u4")
    add(u3, pin.JointModelPY(), "p1")
    ff = add(s1, pin.JointModelFreeFlyer(), "ff")
    u5 = add(ff, _universal(rng, False), "u5")
    add(pl2, pin.JointModelRUBZ(), "ru1")
    add(u5, pin.JointModelPlanar(), "pl4")
    for k, parent in enumerate((u4, u5, pl2, u3)):
        model.addFrame(pin.Frame(f"f{k}", parent, 0, pin.SE3.Random(), pin.FrameType.OP_FRAME))
    return model


def _configurations(model: pin.Model, n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    q0 = pin.neutral(model)
    return np.array(
        [pin.integrate(model, q0, 2.0 * rng.standard_normal(model.nv)) for _ in range(n)]
    )


@pytest.fixture(scope="module", params=[0, 1, 2])
def tree(request) -> pin.Model:
    return _random_tree(request.param)


def test_tree_has_both_kinds_grouped(tree):
    bm = BatchModel(tree)
    assert bm.supported
    names = {tree.joints[j].shortname() for j in range(1, tree.njoints)}
    assert {"JointModelUniversal", "JointModelPlanar"} <= names


def test_placements_and_world_jacobian_match_pinocchio(tree):
    Q = _configurations(tree, 50, 11)
    bk = BatchModel(tree).kinematics(Q)
    data = tree.createData()
    for i, q in enumerate(Q):
        pin.computeJointJacobians(tree, data, q)
        np.testing.assert_allclose(bk.jacobian[i], data.J, rtol=0, atol=TOL)
        for j in range(tree.njoints):
            np.testing.assert_allclose(bk.rotations[i, j], data.oMi[j].rotation, atol=TOL)
            np.testing.assert_allclose(bk.translations[i, j], data.oMi[j].translation, atol=TOL)


def test_frame_placements_and_jacobians_match_pinocchio(tree):
    Q = _configurations(tree, 50, 12)
    bm = BatchModel(tree)
    bk = bm.kinematics(Q)
    data = tree.createData()
    for fid in range(1, tree.nframes):
        R, p = bm.frame_placement(bk, fid)
        J = bm.frame_jacobian(bk, fid)
        for i, q in enumerate(Q):
            pin.computeJointJacobians(tree, data, q)
            pin.updateFramePlacements(tree, data)
            np.testing.assert_allclose(R[i], data.oMf[fid].rotation, atol=TOL)
            np.testing.assert_allclose(p[i], data.oMf[fid].translation, atol=TOL)
            ref = pin.getFrameJacobian(tree, data, fid, pin.LOCAL)
            np.testing.assert_allclose(J[i], ref, atol=TOL)


def test_integrate_matches_pinocchio(tree):
    rng = np.random.default_rng(13)
    Q = _configurations(tree, 50, 14)
    DV = 1.5 * rng.standard_normal((50, tree.nv))
    DV[:10] *= 1e-6  # the series branch of the planar exponential (|ω| < 1e-4)
    DV[10:15] = 0.0
    out = BatchModel(tree).integrate(Q, DV)
    for i in range(50):
        np.testing.assert_allclose(out[i], pin.integrate(tree, Q[i], DV[i]), rtol=0, atol=TOL)


def test_planar_joint_keeps_pinocchio_unnormalised_cos_sin():
    """Pinocchio builds Rz from the stored (cos θ, sin θ) as they are and does not
    renormalise them in integrate; the batched code does the same."""
    model = pin.Model()
    j = model.addJoint(0, pin.JointModelPlanar(), pin.SE3.Random(), "pl")
    model.addJoint(j, pin.JointModelRX(), pin.SE3.Random(), "r")
    q = np.array([[0.3, -0.2, 1.1 * np.cos(0.7), 1.1 * np.sin(0.7), 0.4]])
    dv = np.array([[0.2, 0.5, -0.8, 0.1]])
    bm = BatchModel(model)
    np.testing.assert_allclose(bm.integrate(q, dv)[0], pin.integrate(model, q[0], dv[0]), atol=TOL)
    data = model.createData()
    pin.computeJointJacobians(model, data, q[0])
    bk = bm.kinematics(q)
    np.testing.assert_allclose(bk.rotations[0, 1], data.oMi[1].rotation, atol=TOL)
    np.testing.assert_allclose(bk.jacobian[0], data.J, atol=TOL)


def test_universal_joint_with_non_unit_axes_falls_back():
    """Pinocchio does not normalise a universal joint's axes (its placement is then no
    rotation): such a model is left to Pinocchio pose by pose."""
    model = pin.Model()
    model.addJoint(
        0,
        pin.JointModelUniversal(np.array([2.0, 0, 0]), np.array([0, 1.0, 0])),
        pin.SE3.Identity(),
        "u",
    )
    assert not BatchModel(model).supported


# ------------------------------------------------------------------ through the loader
RPR3 = Path(__file__).parent / "machines" / "rpr3"


def _planar_rpr3() -> pincal.Mechanism:
    """The planar 3-RPR of tests/model/machines/rpr3 with its platform on a URDF planar
    joint (instead of a floating one) and planar pin closures (components x y)."""
    urdf = (RPR3 / "rpr3.urdf").read_text(encoding="utf-8")
    planar = urdf.replace('name="ee_float" type="floating"', 'name="ee_float" type="planar"')
    assert planar != urdf
    sidecar = {
        "closed_loop": [["leg1", "pin1"], ["leg2", "pin2"], ["leg3", "pin3"]],
        "type": ["x y"] * 3,
        "name_mot": ["leg1", "leg2", "leg3"],
        "measured_frame": "end_effector",
        "home": {
            "ee_float": [0.0, 0.0, float(np.cos(0.3)), float(np.sin(0.3))],
            **{f"leg{i}": 0.2066 for i in (1, 2, 3)},
        },
    }
    return pincal.Mechanism(planar, sidecar)


@pytest.fixture(scope="module", params=["rusr_universal", "planar_rpr3"])
def machine(request, tmp_path_factory) -> pincal.Mechanism:
    if request.param == "planar_rpr3":
        return _planar_rpr3()
    folder = tmp_path_factory.mktemp("m")
    return pincal.load_mechanism(write_machine(folder, "rusr", *rusr_universal()))


@pytest.fixture(scope="module")
def rows(machine) -> np.ndarray:
    return pincal.sample_actuators(machine, 20, np.random.default_rng(21))


def test_machine_runs_batched(machine, rows):
    kinds = {machine.model.joints[j].shortname() for j in range(1, machine.model.njoints)}
    assert kinds & {"JointModelUniversal", "JointModelPlanar"}
    assert machine.batch_model.supported and machine.home_branch != 0.0
    qs, bk = machine.configurations_batch(rows)
    assert bk is not None
    for i, row in enumerate(rows):
        np.testing.assert_allclose(qs[i], machine.configuration(row), rtol=0, atol=1e-10)


def test_identification_jacobian_equals_pose_by_pose(machine, rows):
    """As tests/sensitivity/test_batch_points.py: pose_sensitivity at the batch's
    configurations, stacked on the measured components."""
    params = pincal.parameters(machine, "base")
    J = pincal.sensitivity.identification_jacobian(machine, params, rows)
    qs, _ = machine.configurations_batch(rows)
    comp = [COMPONENTS.index(c) for c in machine.measured_components]
    ref = np.concatenate([pose_sensitivity(machine, params, q).jacobian[comp] for q in qs])
    assert J.shape == ref.shape == (len(rows) * len(comp), len(params))
    scale = max(1.0, float(np.max(np.abs(ref))))
    np.testing.assert_allclose(J, ref, rtol=0, atol=1e-10 * scale)
