"""A joint grid over an arm's limits lies inside the joint-limit screen's margin.

The grid's levels include both ends of each range; over a serial arm's whole limits the
joint-limit screen (5 % of each range) removed every row with a joint at an end: all but
2ⁿ rows. `pincal poses aacmm` (bundled) was refused by default, 64 of 4 096 rows left
for 23 parameters (rank 22); a Panda kept 128 of 16 384. ``auto`` uses 3 levels where 4
would pass :data:`AUTO_ROWS` rows (seven joints).
"""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

import pincal
from pincal.cli import main
from pincal.design import (
    AUTO_ROWS,
    ScreenSettings,
    candidate_set,
    default_grid_ranges,
    grid_candidates,
    screen_candidates,
)
from pincal.errors import OptionValueError


def test_the_grid_leaves_the_screens_margin_out_and_the_screen_keeps_every_row():
    mech = pincal.load_mechanism("aacmm")
    lo, hi = np.asarray(mech.actuator_limits, dtype=float).T
    ranges = default_grid_ranges(mech, 0.05)
    assert np.allclose(ranges[:, 0], lo + 0.05 * (hi - lo))
    assert np.allclose(ranges[:, 1], hi - 0.05 * (hi - lo))
    assert np.array_equal(default_grid_ranges(mech), np.stack([lo, hi], axis=1))  # no margin
    for bad in (0.5, -0.1, float("nan")):
        with pytest.raises(OptionValueError, match=r"must be in \[0, 0.5\)"):
            default_grid_ranges(mech, bad)
    params = pincal.parameters(mech, "full")
    grid = grid_candidates(mech, params, 3, joint_margin=0.05)
    _, report = screen_candidates(mech, grid, ScreenSettings(joint_margin=0.05))
    assert report.removed["joint-limit margin"] == 0  # the bounds themselves pass
    whole = grid_candidates(mech, params, 3)  # over the whole limits (the grid before)
    _, report = screen_candidates(mech, whole, ScreenSettings(joint_margin=0.05))
    assert report.removed["joint-limit margin"] == len(whole) - 1  # the centre row alone


def test_the_default_poses_of_the_bundled_arm_cmm_are_designed(tmp_path):
    res = CliRunner().invoke(main, ["poses", "aacmm", "--out", str(tmp_path / "p.csv")])
    assert res.exit_code == 0, res.output  # was: "Jacobian has rank 22 < 23 parameters"
    assert "joint-limit margin" not in res.stderr.split("rejected:")[-1].splitlines()[0]


def test_auto_takes_three_levels_for_seven_joints():
    mech = pincal.load_mechanism("panda")
    assert len(mech.actuated) == 7 and 4**7 > AUTO_ROWS >= 3**7
    params = pincal.parameters(mech, "base")
    auto = candidate_set(mech, params, "auto", 0, joint_margin=0.05)
    assert auto.source == "grid:3" and auto.tried == 3**7
    # a set the grid cannot identify either (72 parameters, rank 34) is not topped up
    full = candidate_set(mech, pincal.parameters(mech, "full"), "auto", 0, joint_margin=0.05)
    assert full.source == "grid:3"
