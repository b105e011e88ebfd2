"""A marker calibration carried to another session: the frame and marker registered again.

Two simulated sessions of one UR5 (1 mm geometric errors): the capture system moved and
turned between them. Calibrated on the first, the robot's geometry predicts the second
session's poses far better than the nominal one, each with its own registration; on a
session of the nominal robot (the errors gone) it predicts worse.
"""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
from click.testing import CliRunner

from pincal.cli import main
from pincal.model import BASE_JOINT, sample_actuators, with_joint_origin
from tests.cli.test_markers_cli import _table, _truth

T_OTHER = pin.SE3(pin.rpy.rpyToMatrix(-0.05, 0.1, 2.0), np.array([-0.8, 1.1, 0.2]))


def _run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_transfer_to_another_session_reports_the_ratio(tmp_path):
    mech, actual = _truth(1e-3)
    _table(tmp_path / "a.csv", actual, sample_actuators(mech, 30, np.random.default_rng(1)),
           2e-5, 2)  # fmt: skip
    moved = with_joint_origin(actual, BASE_JOINT, T_OTHER)
    q_b = sample_actuators(mech, 25, np.random.default_rng(3))
    _table(tmp_path / "b.csv", moved, q_b, 2e-5, 4)
    cols = ("--marker-columns", "mx,my,mz", "--length-unit", "mm")
    r = _run("calibrate", "ur5", "--link", "wrist_3_link", "--data", tmp_path / "a.csv", *cols,
             "--out", tmp_path / "cal")  # fmt: skip
    assert r.exit_code == 0, r.output
    out = _run("validate", tmp_path / "cal", "--data", tmp_path / "b.csv", "--json")
    assert out.exit_code == 0, out.output
    transfer = json.loads(out.output)["transfer"]
    assert transfer["baseline"]["name"] == "registration only"
    assert transfer["ratio"] < 0.2  # 1 mm errors against 20 µm of noise
    text = _run("validate", tmp_path / "cal", "--data", tmp_path / "b.csv").output
    assert "ratio calibrated / registration only" in text and "carries over" in text
    # the same-set-up rows keep the calibrated registration: robots, not models
    assert "  nominal robot " in text and "  calibrated robot " in text
    assert "nominal model" not in text
    # the same poses on the nominal robot: the calibrated geometry is now the wrong one
    _, nominal = _truth(0.0)
    _table(tmp_path / "c.csv", with_joint_origin(nominal, BASE_JOINT, T_OTHER), q_b, 2e-5, 4)
    out = _run("validate", tmp_path / "cal", "--data", tmp_path / "c.csv", "--json")
    assert out.exit_code == 0, out.output
    assert json.loads(out.output)["transfer"]["ratio"] > 1.0
