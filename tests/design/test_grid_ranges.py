"""The default joint grid spans the joint motion of a declared pose workspace."""

from __future__ import annotations

import numpy as np
import pytest

import pincal
from pincal.design import default_grid_ranges, grid_candidates


@pytest.fixture(scope="module")
def hexaslide():
    return pincal.load_mechanism("hexaslide_6pus")


def test_a_declared_joint_stroke_does_not_widen_the_grid_past_the_pose_workspace(hexaslide):
    ranges = default_grid_ranges(hexaslide)
    stroke = np.array([hexaslide.workspace.joints[a] for a in hexaslide.actuated])
    assert np.all(ranges[:, 0] >= stroke[:, 0]) and np.all(ranges[:, 1] <= stroke[:, 1])
    # the carriages' rails are 0.22 m; the pose workspace moves each by a few centimetres
    assert np.all(ranges[:, 1] - ranges[:, 0] < 0.5 * (stroke[:, 1] - stroke[:, 0]))
    home = hexaslide.actuators_of(hexaslide.q_home)
    assert np.all((ranges[:, 0] <= home) & (home <= ranges[:, 1]))


def test_a_coarse_grid_over_it_assembles_and_lands_in_the_workspace(hexaslide):
    params = pincal.parameters(hexaslide, "pus54")
    # two levels: the 64 corners of the joint box. Over the whole rails (the grid before)
    # none of them assembled; over the workspace's joint motion some do, and some of
    # those lie inside the pose box
    found = grid_candidates(hexaslide, params, 2)
    assert found.tried == 64 and len(found) > 0
