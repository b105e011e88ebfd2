"""A URDF re-rooted at another link is the same robot seen from there.

Checked against Pinocchio's model of the URDF as shipped: for random configurations
of the whole tree, every link's placement relative to the new root is the same.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from pincal.errors import ModelFileError, UnknownNameError
from pincal.model import UrdfTree, chain_joints, reroot_urdf, resolve_named


def _q_by_name(src: pin.Model, dst: pin.Model, q: np.ndarray) -> np.ndarray:
    out = pin.neutral(dst)
    for j in range(1, src.njoints):
        k = dst.getJointId(src.names[j])
        i, n = src.idx_qs[j], src.nqs[j]
        out[dst.idx_qs[k] : dst.idx_qs[k] + n] = q[i : i + n]
    return out


@pytest.mark.parametrize(
    ("robot", "root", "links"),
    [
        ("talos", "left_sole_link", ["gripper_left_base_link", "arm_right_7_link", "head_2_link"]),
        ("talos", "arm_left_7_link", ["right_sole_link", "base_link"]),
        ("tiago", "torso_lift_link", ["arm_7_link", "base_footprint", "wheel_left_link"]),
    ],
)
def test_rerooted_tree_keeps_every_relative_placement(robot, root, links):
    xml = resolve_named(robot).urdf.read_text()
    m0 = pin.buildModelFromXML(xml)
    m1 = pin.buildModelFromXML(reroot_urdf(xml, root))
    assert m1.nq == m0.nq and m1.frames[m1.getFrameId(root)].parentJoint == 0
    d0, d1 = m0.createData(), m1.createData()
    rng = np.random.default_rng(0)
    for _ in range(5):
        q0 = pin.randomConfiguration(m0, -np.ones(m0.nq), np.ones(m0.nq))
        q0 = q0 + rng.uniform(-0.5, 0.5, m0.nq)  # beyond the limits too: values carry over
        pin.framesForwardKinematics(m0, d0, q0)
        pin.framesForwardKinematics(m1, d1, _q_by_name(m0, m1, q0))
        for link in links:
            T0 = d0.oMf[m0.getFrameId(root)].inverse() * d0.oMf[m0.getFrameId(link)]
            T1 = d1.oMf[m1.getFrameId(link)]
            assert np.abs(T0.homogeneous - T1.homogeneous).max() < 1e-12


def test_chain_joints_go_up_then_down():
    tree = UrdfTree(resolve_named("talos").urdf.read_text())
    chain = chain_joints(tree, "left_sole_link", "arm_left_2_link")
    movable = [j for j in chain if tree.joints[j].movable]
    assert movable == [f"leg_left_{k}_joint" for k in range(6, 0, -1)] + [
        "torso_1_joint", "torso_2_joint", "arm_left_1_joint", "arm_left_2_joint"]  # fmt: skip
    down = tree.ancestors("arm_left_2_link")
    assert chain_joints(tree, tree.root_link, "arm_left_2_link") == down


def test_reroot_refusals():
    xml = resolve_named("talos").urdf.read_text()
    with pytest.raises(UnknownNameError, match="left_sole"):
        reroot_urdf(xml, "left_sole")
    assert reroot_urdf(xml, UrdfTree(xml).root_link) == xml
    joint = 'name="torso_1_joint" type='
    floating = xml.replace(joint + '"revolute"', joint + '"floating"')
    assert floating != xml
    with pytest.raises(ModelFileError, match="torso_1_joint.*floating"):
        reroot_urdf(floating, "arm_left_7_link")
