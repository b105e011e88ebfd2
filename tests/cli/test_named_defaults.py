"""Arms by name without an SRDF reference pose (ur5, ur10): a searched regular home and
a floor under drawn poses, through the CLI; a sidecar's home and floor win."""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.io import read_measurements, read_pose_file
from pincal.model import DEFAULT_FLOOR, Mechanism, conditioning, load_mechanism


def run(args: list[str]):
    return CliRunner().invoke(main, args)


def lowest_point(mech: Mechanism, q_act: np.ndarray) -> float:
    """Lowest height [m] of the joint origins from the elbow on and of the measured frame.

    (The UR's first two joint origins keep their height, 89 mm on ur5, whatever q.)
    """
    data = mech.model.createData()
    q = mech.with_actuators(mech.q_home, q_act)
    pin.framesForwardKinematics(mech.model, data, q)
    z = [data.oMi[j].translation[2] for j in range(3, mech.model.njoints)]
    z.append(data.oMf[mech.frame_id(mech.measured_frame)].translation[2])
    return float(min(z))


@pytest.mark.parametrize("robot", ["ur5", "ur10"])
def test_arm_by_name_gets_a_regular_home_and_poses_above_the_floor(robot, tmp_path):
    res = run(["info", robot])
    assert res.exit_code == 0, res.output
    assert "home (searched): " in res.output and "regular configuration of" in res.output
    assert "home is a singular" not in res.output
    assert f"{DEFAULT_FLOOR * 1e3:.0f} mm above the base plane" in res.output
    mech = load_mechanism(robot)
    q0 = mech.with_actuators(mech.q_home, np.zeros(len(mech.actuated)))
    assert conditioning(mech, q0) < 1e-9  # the URDF's q = 0 is singular
    assert conditioning(mech, mech.q_home) > 0.05
    assert lowest_point(mech, mech.actuators_of(mech.q_home)) >= DEFAULT_FLOOR
    assert lowest_point(mech, np.zeros(len(mech.actuated))) < DEFAULT_FLOOR  # q = 0 is not
    res = run(["simulate", robot, "--random", "40", "--out", str(tmp_path / "m.csv")])
    assert res.exit_code == 0, res.output
    res = run(["poses", robot, "--count", "12", "--out", str(tmp_path / "p.csv")])
    assert res.exit_code == 0, res.output
    assert "below floor" in res.output
    assert "pincal: note: home (searched): " in res.stderr  # every command says it
    posed = read_pose_file(tmp_path / "p.csv").q_act
    assert posed is not None and len(posed) == 12
    for rows in (read_measurements(tmp_path / "m.csv", mech).q_act, posed):
        assert min(lowest_point(mech, r) for r in rows) >= DEFAULT_FLOOR - 1e-9


def test_ur5_acceptance_after_a_clean_simulated_calibration(tmp_path):
    p, m, cal = (str(tmp_path / n) for n in ("p.csv", "m.csv", "cal"))
    for args in (
        ["poses", "ur5", "--count", "20", "--out", p],
        ["simulate", "ur5", "--poses", p, "--out", m],
        ["calibrate", "ur5", "--data", m, "--out", cal],
    ):
        res = run(args)
        assert res.exit_code == 0, res.output
    res = run(["acceptance", "ur5", "--calibrated", cal, "--json"])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout.strip().splitlines()[-1])
    before, after = np.array(doc["before"]["AP_p"]), np.array(doc["after"]["AP_p"])
    assert before.min() > 1e-3  # simulated errors of 1 mm / 10 mrad: mm at the tool [m]
    assert after.max() < 2e-5  # after calibration: µm (noise 10 µm, 20 poses) [m]
    assert doc["cube"]["bounds"][2][0] >= DEFAULT_FLOOR - 1e-9  # the sampled z above the floor


def test_a_sidecar_home_and_floor_win(tmp_path):
    home = {"shoulder_lift_joint": -1.2, "elbow_joint": 1.5, "wrist_2_joint": -1.5}
    side = tmp_path / "cell.yaml"
    side.write_text(
        "home: {shoulder_lift_joint: -1.2, elbow_joint: 1.5, wrist_2_joint: -1.5}\n"
        "workspace: {floor: false}\n"
    )
    res = run(["info", "ur5", "--sidecar", str(side)])
    assert res.exit_code == 0, res.output
    assert "home (searched)" not in res.output and "above the base plane" not in res.output
    mech = load_mechanism("ur5", sidecar=side)
    got = dict(zip(mech.actuated, mech.actuators_of(mech.q_home), strict=True))
    assert got == pytest.approx({**dict.fromkeys(mech.actuated, 0.0), **home})
    assert mech.workspace.floor is None
    # without the floor, the same seeded draws go through it
    res = run(["simulate", "ur5", "--sidecar", str(side), "--random", "40",
               "--out", str(tmp_path / "m.csv")])  # fmt: skip
    assert res.exit_code == 0, res.output
    rows = read_measurements(tmp_path / "m.csv", mech).q_act
    assert min(lowest_point(mech, r) for r in rows) < 0
    # a floor of the user's own, and a bad one
    side.write_text("workspace: {floor: 0.3}\n")
    assert load_mechanism("ur5", sidecar=side).workspace.floor == 0.3
    res = run(["simulate", "ur5", "--sidecar", str(side), "--random", "10",
               "--out", str(tmp_path / "f.csv")])  # fmt: skip
    assert res.exit_code == 0, res.output
    rows = read_measurements(tmp_path / "f.csv", mech).q_act
    assert min(lowest_point(mech, r) for r in rows) >= 0.3 - 1e-9
    side.write_text("workspace: {floor: low}\n")
    res = run(["info", "ur5", "--sidecar", str(side)])
    assert res.exit_code == 1 and "workspace.floor must be a height [m]" in res.output
