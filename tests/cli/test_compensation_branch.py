"""Compensation stays on the branch of each target's start command (serial arm, parallel machine).

Through the CLI: ``poses`` → ``simulate`` → ``calibrate`` → ``compensate`` on ur5 loaded by
name and on the planar 3-RRR of tests/model/machines/rrr3; the compensated commands must
stay next to the nominal commands of the targets file, and a solution on another branch
is refused unless allowed.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.compensation import BRANCH_STEP_RAD, branch_change, compensate
from pincal.io import read_calibration, read_commands, read_pose_file, write_poses
from pincal.model import load_mechanism

RRR3 = str(Path(__file__).parents[1] / "model" / "machines" / "rrr3" / "rrr3.urdf")


def _ok(args: list[str]):
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output + (res.stderr or "")
    return res


def _campaign(tmp: Path, model: str, count: int, preset: list[str], params: list[str]) -> Path:
    """poses → simulate → calibrate; returns the calibration directory."""
    _ok(["poses", model, "--count", str(count), "--candidates", "random:120",
         "--restarts", "1", *preset, "--out", str(tmp / "poses.csv")])  # fmt: skip
    _ok(["simulate", model, "--poses", str(tmp / "poses.csv"), *params,
         "--out", str(tmp / "m.csv")])  # fmt: skip
    _ok(["calibrate", model, "--data", str(tmp / "m.csv"), *params, "--out", str(tmp / "cal")])
    return tmp / "cal"


def _check_commands(tmp: Path, cal_dir: Path, summary: dict) -> None:
    """Written commands reach their targets on the calibrated model, next to the nominal."""
    cal = read_calibration(cal_dir)
    mech = cal.calibrated()
    pf = read_pose_file(tmp / "poses.csv")
    _, q = read_commands(tmp / "c.csv", mech)[:2]
    reached = [i for i in range(len(pf.poses)) if i not in summary["unreachable"]]
    assert len(reached) == summary["commands"] == len(q)
    dq = np.abs(q - pf.q_act[reached])
    assert dq.max() <= BRANCH_STEP_RAD
    assert summary["largest_step"]["rad"]["value"] == pytest.approx(dq.max(), rel=1e-9)
    cols = [["x", "y", "z", "rx", "ry", "rz"].index(c) for c in summary["components"]]
    for i, row in zip(reached, q, strict=True):
        T, got = pf.poses[i], mech.forward(row)
        err = np.r_[got.translation - T.translation, pin.log3(T.rotation.T @ got.rotation)]
        assert np.abs(err[cols]).max() < 1e-8


def test_ur5_by_name_compensates_from_the_nominal_commands(tmp_path):
    cal = _campaign(tmp_path, "ur5", 24, [], [])
    res = _ok(["compensate", str(cal), "--targets", str(tmp_path / "poses.csv"),
               "--out", str(tmp_path / "c.csv"), "--skip-unreachable", "--json"])  # fmt: skip
    summary = json.loads(res.stdout)
    assert summary["starts"].startswith("the nominal command of each target")
    assert summary["commands"] > summary["targets"] / 2
    for k in summary["unreachable"]:  # each refusal says why: no IK, a limit, or a branch
        why = summary["reasons"][str(k)]
        assert "after Newton" in why or "outside [" in why or "another branch" in why
        assert ("another branch" in why) == (str(k) in summary["branch_changes"])
    _check_commands(tmp_path, cal, summary)
    text = _ok(["compensate", str(cal), "--targets", str(tmp_path / "poses.csv"),
                "--out", str(tmp_path / "c.csv"), "--skip-unreachable"]).stdout  # fmt: skip
    assert "largest |Δq| from the start:" in text and " rad (" in text


def test_parallel_machine_compensates_from_the_nominal_commands(tmp_path):
    cal = _campaign(tmp_path, RRR3, 20, ["--preset", "base"], ["--params", "base"])
    res = _ok(["compensate", str(cal), "--targets", str(tmp_path / "poses.csv"),
               "--out", str(tmp_path / "c.csv"), "--skip-unreachable", "--json"])  # fmt: skip
    summary = json.loads(res.stdout)
    assert summary["components"] == ["x", "y", "rz"] and not summary["branch_changes"]
    assert all("outside [" in summary["reasons"][str(k)] for k in summary["unreachable"])
    _check_commands(tmp_path, cal, summary)
    # without commands in the targets file: each target starts from the nearest solved one
    pf = read_pose_file(tmp_path / "poses.csv")
    write_poses(tmp_path / "bare.csv", pf.poses)
    res = _ok(["compensate", str(cal), "--targets", str(tmp_path / "bare.csv"),
               "--out", str(tmp_path / "c2.csv"), "--skip-unreachable", "--json"])  # fmt: skip
    bare = json.loads(res.stdout)
    assert "nearest solved" in bare["starts"] and bare["unreachable"] == summary["unreachable"]
    _, q2 = read_commands(tmp_path / "c2.csv", read_calibration(cal).calibrated())[:2]
    _, q1 = read_commands(tmp_path / "c.csv", read_calibration(cal).calibrated())[:2]
    np.testing.assert_allclose(q2, q1, atol=1e-7)  # the same branch as the nominal commands


def test_a_far_start_is_refused_as_a_branch_change_unless_allowed():
    arm = load_mechanism("ur5")
    q_a = np.array([0.3, -1.2, 1.4, -1.5, -1.4, 0.2])
    target = arm.forward(q_a)
    far = q_a + np.array([0.0, 0.0, 0.0, 0.0, 0.0, 2 * np.pi])  # same tip pose, wrist turned
    refused = compensate(arm, [target], starts=[q_a + np.r_[0, 0, 0, 0, 0, 1.2]])
    assert refused.unreachable == (0,) and 0 in refused.branch_changes
    assert "another branch" in refused.reasons[0] and "wrist_3_joint" in refused.reasons[0]
    allowed = compensate(
        arm, [target], starts=[q_a + np.r_[0, 0, 0, 0, 0, 1.2]], allow_branch_change=True
    )
    assert allowed.reachable[0] and 0 in allowed.branch_changes
    # a 2π turn of a revolute actuator is another command for the same pose: a change
    assert "moved 6.283 rad" in branch_change(arm, q_a, far, None, arm.configuration(far),
                                              ("rad",) * 6)  # fmt: skip


def test_the_elbow_flip_is_a_branch_change_by_the_jacobian_sign():
    arm = load_mechanism("ur5")
    units = ("rad",) * 6
    q_a = np.array([0.3, -1.2, 1.4, -1.5, -1.4, 0.2])
    assert branch_change(arm, q_a, q_a + 0.01, None, arm.configuration(q_a + 0.01), units) == ""
    # elbow up / down for the same tip pose: the IK from a start with the elbow bent the
    # other way (a singularity at elbow = 0 lies between them)
    T = arm.forward(q_a)
    guess = arm.configuration(np.array([0.3, -0.2, -1.4, -2.5, -1.4, 0.2]))
    q_b = arm.actuators_of(arm.inverse_configuration(T, guess))
    assert np.sign(q_b[2]) != np.sign(q_a[2])
    with_bound = branch_change(arm, q_a, q_b, None, arm.configuration(q_b), units)
    assert with_bound  # a different arm configuration is caught
    from pincal.compensation._branch import det_sign

    assert det_sign(arm, q_a) == -det_sign(arm, q_b) != 0
