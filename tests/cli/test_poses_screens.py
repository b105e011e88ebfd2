"""`pincal poses` chooses poses a real machine can execute (issue 37, item 3).

The issue's command, `pincal poses ur5 --count 40 --candidates random:300`, chose folded
elbows (3.138, −3.046 rad: self-collision) and a stretched one (0.0056 rad: singular).
"""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.compensation import compensate
from pincal.design import CollisionChecker, actuator_sigma_min
from pincal.io import read_commands, read_poses
from pincal.model import load_mechanism, parameters


@pytest.fixture(scope="module")
def ur5_design(tmp_path_factory):
    out = tmp_path_factory.mktemp("poses") / "poses.csv"
    args = ["poses", "ur5", "--count", "40", "--candidates", "random:300", "--out", str(out)]
    res = CliRunner().invoke(main, [*args, "--json"])
    assert res.exit_code == 0, res.output
    return out, json.loads(res.stdout), res.stderr


def test_ur5_design_has_no_collision_singularity_or_branch_change(ur5_design):
    out, summary, stderr = ur5_design
    removed = summary["screens_removed"]
    assert set(removed) == {
        "joint-limit margin", "singularity margin", "self-collision", "compensation"
    }  # fmt: skip
    assert removed["self-collision"] > 0 and removed["singularity margin"] > 0
    assert "self-collision" in stderr and "geometry pairs checked" in stderr
    mech = load_mechanism("ur5")
    _, q_act = read_commands(out.with_suffix(".commands.csv"), mech)
    assert len(q_act) == 40
    elbow = q_act[:, 2]
    assert np.all(np.abs(elbow) > 0.02) and np.all(np.abs(elbow) < 3.0)  # the poses
    checker = CollisionChecker(mech)
    assert not any(checker.collisions(q)[0] for q in q_act)
    assert not _failed_on_further_draws(mech, out, q_act)
    sigma, _ = actuator_sigma_min(mech, q_act)
    assert sigma.min() > 0.01  # away from the stretched/folded singularities


def _failed_on_further_draws(mech, out, q_act, draws: int = 20) -> dict[tuple[int, int], str]:
    """{(draw, pose): why} of the designed poses that do not compensate, from their own
    commands, on further draws of ±1 mm / ±10 mrad errors than the screen's."""
    params = parameters(mech, "full")
    bound = np.where(np.array(params.units) == "m", 1e-3, 10e-3)
    rng = np.random.default_rng(2026)
    failed = {}
    for d in range(draws):
        displaced = params.apply(mech, rng.uniform(-bound, bound))
        result = compensate(displaced, read_poses(out), starts=q_act)
        failed.update({(d, i): why for i, why in result.reasons.items()})
    return failed


def test_screens_can_be_relaxed_and_obstacles_declared(tmp_path):
    out = tmp_path / "p.csv"
    args = ["poses", "ur5", "--count", "20", "--candidates", "random:150", "--out", str(out),
            "--singular-margin", "0", "--joint-margin", "0", "--reach-errors", "none",
            "--obstacle", "0 0 -30 3000 3000 60", "--json"]  # fmt: skip
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    removed = json.loads(res.stdout)["screens_removed"]
    assert "singularity margin" not in removed and removed["joint-limit margin"] == 0
    assert "compensation" not in removed and removed["obstacle collision"] > 0
    # a table top just under the base: kept poses keep every link above it
    mech = load_mechanism("ur5")
    _, q_act = read_commands(out.with_suffix(".commands.csv"), mech)
    data = mech.model.createData()
    for q in q_act:
        pin.framesForwardKinematics(mech.model, data, q)
        assert data.oMf[mech.frame_id("wrist_3_link")].translation[2] > 0


@pytest.mark.parametrize(
    ("option", "value"),
    [("--obstacle", "1 2 3"), ("--reach-errors", "1"), ("--joint-margin", "0.7")],
)
def test_bad_screen_options_fail_in_one_line(tmp_path, option, value):
    res = CliRunner().invoke(
        main, ["poses", "ur5", "--out", str(tmp_path / "p.csv"), option, value]
    )
    assert res.exit_code == 1, res.output
    assert option.lstrip("-").split("-")[0] in res.stderr and "Traceback" not in res.output


def test_kinova_design_has_no_collision_or_singular_pose(tmp_path):
    """Kinova (Jaco 2, a hand with fingers: collisions checked on full configurations).
    Three random error draws of 1 mm / 10 mrad alone let poses through that failed on
    1–3 of 10 further draws (the wrist singularity, the edge of the reach); with each
    candidate's critical draws every pose compensates on 20 further draws."""
    out = tmp_path / "kinova.csv"
    args = ["poses", "kinova", "--count", "20", "--candidates", "random:150", "--out", str(out)]
    res = CliRunner().invoke(main, [*args, "--json"])
    assert res.exit_code == 0, res.output
    removed = json.loads(res.stdout)["screens_removed"]
    assert "self-collision" in removed and "geometry pairs checked" in res.stderr
    mech = load_mechanism("kinova")
    _, q_act = read_commands(out.with_suffix(".commands.csv"), mech)
    assert len(q_act) == 20
    checker = CollisionChecker(mech)  # full configurations: the hand's fingers too
    assert not any(checker.collisions(mech.configuration(q))[0] for q in q_act)
    sigma, _ = actuator_sigma_min(mech, q_act)
    assert sigma.min() > 0.01
    assert not _failed_on_further_draws(mech, out, q_act)
