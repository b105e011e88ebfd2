"""A continuous joint's compensated command stays next to its start across ±π.

A continuous joint's configuration holds (cos θ, sin θ), read back in (−π, π]: a
correction of −10 mrad from a start at −π + 5 mrad read +π − 5 mrad, 2π away, and the
target was refused as a branch change (a Kinova's fourth joint on a designed pose).
"""

from __future__ import annotations

import numpy as np
import pytest

from pincal.compensation import compensate
from pincal.model import load_mechanism, parameters


def test_a_correction_across_pi_is_not_a_branch_change():
    mech = load_mechanism("kinova")
    joint = mech.actuated[3]
    assert mech.tree.joints[joint].type == "continuous"
    params = parameters(mech, "full")
    values = np.zeros(len(params))
    values[params.names.index(f"{joint}.offset")] = 0.01  # the joint reads 10 mrad short
    displaced = params.apply(mech, values)
    start = np.array([0.3, 2.9, 1.2, -np.pi + 0.005, 2.5, 0.4])
    target = mech.frame_placement(mech.configuration(start))
    result = compensate(displaced, [target], starts=start[None])
    assert result.reachable.all(), result.reasons
    assert not result.branch_changes
    assert result.q_act[0, 3] == pytest.approx(start[3] - 0.01, abs=1e-6)  # not + 2π
    assert np.allclose(np.delete(result.q_act[0], 3), np.delete(start, 3), atol=1e-6)
