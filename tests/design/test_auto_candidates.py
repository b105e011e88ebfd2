"""The default candidate spec ``auto``: the joint grid, random workspace poses when it keeps few."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

import pincal
from pincal.cli import main
from pincal.design import AUTO_LEAST, candidate_set, parse_candidate_spec


def test_where_the_grid_keeps_enough_auto_is_the_grid():
    mech = pincal.load_mechanism("stewart_6ups")
    params = pincal.parameters(mech, "stewart42")
    auto, grid = candidate_set(mech, params, "auto", 0), candidate_set(mech, params, "grid:4", 0)
    assert len(auto) == len(grid) >= AUTO_LEAST and auto.source == "grid:4"
    assert np.array_equal(auto.q_act, grid.q_act)


def test_a_thin_pose_workspace_gets_random_workspace_poses():
    """The wedge's grid keeps 4 of 64 rows; auto adds random poses inside the pose box."""
    mech = pincal.load_mechanism("wedge3")
    params = pincal.parameters(mech, "patent")
    grid = candidate_set(mech, params, "grid:4", 0)
    assert len(grid) < AUTO_LEAST
    auto = candidate_set(mech, params, "auto", 0)
    assert len(auto) >= AUTO_LEAST and auto.tried == grid.tried + 500
    assert np.array_equal(auto.q_act[: len(grid)], grid.q_act)  # the grid's rows first
    assert "grid:4 kept" in auto.source and auto.summary().startswith(f"{len(auto)} of ")
    box = mech.workspace.pose
    x = auto.positions[:, 0] - mech.forward(mech.actuators_of(mech.q_home)).translation[0]
    assert np.all(np.abs(x) <= max(abs(v) for v in box["x"]) + 1e-9)


def test_a_grid_past_the_row_bound_is_replaced_by_random_poses():
    mech = pincal.load_mechanism("stewart_6ups")
    params = pincal.parameters(mech, "stewart42")
    auto = candidate_set(mech, params, "auto", 0, max_candidates=1000)  # 4^6 rows > 1000
    assert auto.tried == 500 and "would be 4096 rows" in auto.source


def test_auto_parses_and_the_default_poses_command_works_on_the_wedge(tmp_path):
    assert parse_candidate_spec("auto")[0] == "auto"
    with pytest.raises(pincal.PincalError, match="auto, grid:LEVELS"):
        parse_candidate_spec("automatic")
    res = CliRunner().invoke(main, ["poses", "wedge3", "--out", str(tmp_path / "p.csv")])
    assert res.exit_code == 0, res.output  # grid:4 alone was refused: 4 poses for 18
    assert "random:500 added" in res.stderr


def test_auto_counts_the_grid_poses_the_callers_screens_keep():
    mech = pincal.load_mechanism("stewart_6ups")
    params = pincal.parameters(mech, "stewart42")
    auto = candidate_set(mech, params, "auto", 0, usable=lambda c: c.subset(range(36)))
    assert "grid:4 kept 36 of 4096 after the screens, random:500 added" in auto.source
    assert auto.tried == 4096 + 500
    # enough poses, but too alike to identify the parameters: topped up as well
    same = candidate_set(mech, params, "auto", 0, usable=lambda c: c.subset([0] * 200))
    assert "grid:4 kept 200 of 4096 after the screens, of rank 6 < 42" in same.source


@pytest.mark.skipif(
    "panda_collision" not in pincal.model.example_robot_names(),
    reason="panda_collision is not in this example-robot-data",
)
def test_an_arm_whose_grid_the_collision_screen_empties_is_designed(tmp_path):
    """The Panda's collision capsules touch at most folded grid poses: the screens kept 81
    of 2 187, which identify 22 of 34 parameters (`poses` refused: rank 22 < 34); a
    Baxter arm beside its body kept 147, enough poses, of rank 30 < 34."""
    res = CliRunner().invoke(main, ["poses", "panda_collision", "--out", str(tmp_path / "p.csv")])
    assert res.exit_code == 0, res.output
    assert "kept 81 of 2187 after the screens, of rank 22 < 34, random:500 added" in res.stderr
    args = ["poses", "baxter", "--frame", "left_gripper", "--out", str(tmp_path / "b.csv")]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output  # was: "Jacobian has rank 30 < 34 parameters"
    assert "kept 147 of 2187 after the screens, of rank 30 < 34" in res.stderr
