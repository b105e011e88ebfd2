"""A displaced mechanism's URDF tree is the tree of its text, without re-parsing it."""

from __future__ import annotations

import numpy as np
import pytest

import pincal
from pincal.model import Mechanism
from pincal.model.files._urdf import UrdfTree


@pytest.mark.parametrize("name", ["stewart_6ups", "ur10", "aacmm", "wedge3"])
def test_displaced_tree_equals_the_parsed_text(name):
    mech = pincal.load_mechanism(name)
    params = pincal.parameters(mech, "full")
    values = np.random.default_rng(4).normal(0.0, 1e-3, len(params))
    moved = params.apply(mech, values)
    parsed = UrdfTree(moved.urdf_xml)
    assert parsed.links == moved.tree.links
    assert parsed.parent_joint == moved.tree.parent_joint
    assert parsed.depth == moved.tree.depth
    assert list(parsed.joints) == list(moved.tree.joints)
    for j, a in parsed.joints.items():
        b = moved.tree.joints[j]
        assert (a.name, a.type, a.parent, a.child) == (b.name, b.type, b.parent, b.child)
        np.testing.assert_array_equal(a.origin.homogeneous, b.origin.homogeneous)
        np.testing.assert_array_equal(a.axis, b.axis)
    assert moved.tree.ancestors(mech.frame_link(mech.measured_frame)) == parsed.ancestors(
        mech.frame_link(mech.measured_frame)
    )
    # a second displacement from either tree writes the same text
    again = {j: moved.tree.joints[j].origin for j in params.joints[:3]}
    assert moved.tree.with_origins(again) == parsed.with_origins(again)
    # and the mechanism (derived in place, not rebuilt: the placements are composed in
    # another order than Pinocchio's parser does, so they agree to rounding) equals one
    # built from the text alone; tests/model/test_placements.py compares everything
    rebuilt = Mechanism(
        moved.urdf_xml,
        mech.sidecar,
        name=mech.name,
        measured_frame=mech.measured_frame,
        q_guess=mech.q_home,
        options=mech.options,
    )
    np.testing.assert_allclose(rebuilt.q_home, moved.q_home, rtol=0, atol=1e-15)
    for a, b in zip(rebuilt.model.jointPlacements, moved.model.jointPlacements, strict=True):
        np.testing.assert_allclose(a.homogeneous, b.homogeneous, rtol=0, atol=1e-15)
    # the nominal tree is untouched
    np.testing.assert_array_equal(
        UrdfTree(mech.urdf_xml).joints[params.joints[0]].origin.homogeneous,
        mech.tree.joints[params.joints[0]].origin.homogeneous,
    )


def test_displacing_an_unknown_joint_names_it():
    mech = pincal.load_mechanism("ur10")
    with pytest.raises(pincal.errors.UnknownNameError, match="no_such_joint"):
        mech.tree.displaced({"no_such_joint": next(iter(mech.tree.joints.values())).origin})
