"""Random poses keep SAMPLE_MARGIN of every sampling range free at either end (issue 36).

Before, random poses reached the actuator limits themselves: a calibrated model then
pushes such a pose outside them, where ``simulate`` and ``compensate`` refuse it.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from pincal.model import SAMPLE_MARGIN, WORKSPACE_POSE_KEYS, load_mechanism, sample_actuators
from tests.open_world.first_machines import SPM_RANGE, spherical_3rrr
from tests.open_world.machines import write_machine


def test_actuator_draws_keep_the_margin(tmp_path):
    mech = load_mechanism(write_machine(tmp_path, "spm", *spherical_3rrr()))
    rows = sample_actuators(mech, 300, np.random.default_rng(0))
    lo, hi = SPM_RANGE
    inner = (lo + SAMPLE_MARGIN * (hi - lo), hi - SAMPLE_MARGIN * (hi - lo))
    assert SAMPLE_MARGIN == 0.05
    assert rows.min() >= inner[0] and rows.max() <= inner[1]
    # and still spread over the inner range (the margin, not a collapse)
    assert rows.min() < inner[0] + 0.05 and rows.max() > inner[1] - 0.05


def test_pose_draws_keep_the_margin(stewart):
    from pincal.model import sample_pose

    lim = stewart.workspace.pose
    assert lim
    home = stewart.frame_placement(stewart.q_home)
    rng = np.random.default_rng(1)
    for _ in range(200):
        T = sample_pose(stewart, rng)
        values = dict(
            zip(
                WORKSPACE_POSE_KEYS,
                (*T.translation, *pin.log3(home.rotation.T @ T.rotation)),
                strict=True,
            )
        )
        for key, (lo, hi) in lim.items():
            gap = SAMPLE_MARGIN * (hi - lo) - 1e-12
            assert lo + gap <= values[key] <= hi - gap, key
