"""The command-line loop: simulate → calibrate → compensate; one-line errors."""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
from click.testing import CliRunner

from pincal.cli import main
from pincal.io import (
    read_commands,
    read_measurements,
    write_poses,
)
from pincal.model import load_mechanism, parameters, sample_actuators


def test_simulate_calibrate_compensate_loop(tmp_path):
    runner = CliRunner()
    meas = tmp_path / "m.csv"
    res = runner.invoke(
        main,
        [
            "simulate",
            "hexaslide_6pus",
            "--random",
            "14",
            "--errors",
            "seed:4",
            "--noise",
            "0.001,0.005",
            "--out",
            str(meas),
        ],
    )
    assert res.exit_code == 0, res.output
    truth = json.loads((tmp_path / "m.truth.json").read_text())
    res = runner.invoke(
        main,
        [
            "calibrate",
            "hexaslide_6pus",
            "--data",
            str(meas),
            "--out",
            str(tmp_path / "cal"),
            "--json",
        ],
    )
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout)
    assert doc == json.loads((tmp_path / "cal" / "identification.json").read_text())
    assert doc["identifiability"]["rank"] == 54
    assert 0.3 < doc["reduced_chi2"] < 2.0  # noise-limited fit (GN may stop "no decrease")
    assert (tmp_path / "cal" / "report.txt").read_text().startswith("pincal calibration")
    true = {p["name"]: p["value"] for p in truth["parameters"]}
    z = [(p["value"] - true[p["name"]]) / p["std"] for p in doc["parameters"]]
    assert np.sqrt(np.mean(np.square(z))) < 2.0  # errors consistent with the reported std
    # compensation: the actual machine at the compensated commands hits the targets
    nominal = load_mechanism("hexaslide_6pus")
    params = parameters(nominal, truth["preset"])
    actual = params.apply(nominal, np.array([true[n] for n in params.names]))
    targets = [
        pin.SE3(pin.rpy.rpyToMatrix(0.05, -0.08, 0.1), np.array([0.02, -0.01, 0.45])),
        pin.SE3(np.eye(3), np.array([-0.03, 0.02, 0.47])),
        pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.95])),  # unreachable
    ]
    write_poses(tmp_path / "targets.csv", targets)
    cmd = [
        "compensate",
        str(tmp_path / "cal"),
        "--targets",
        str(tmp_path / "targets.csv"),
        "--out",
        str(tmp_path / "c.csv"),
    ]
    res = runner.invoke(main, cmd)
    assert res.exit_code == 1
    assert "targets [2] are unreachable" in res.stderr and "Traceback" not in res.output
    res = runner.invoke(main, [*cmd, "--skip-unreachable"])
    assert res.exit_code == 0, res.output
    idx, q = read_commands(tmp_path / "c.csv", nominal)
    assert idx.tolist() == [0, 1]
    for T, row in zip(targets[:2], q, strict=True):
        err_after = np.linalg.norm(actual.forward(row).translation - T.translation)
        err_before = np.linalg.norm(actual.forward(nominal.inverse(T)).translation - T.translation)
        assert err_after < 0.02e-3 < err_before


def test_bad_input_is_one_line_exit_1(tmp_path):
    runner = CliRunner()
    bad = tmp_path / "bad.csv"
    bad.write_text("# pincal measurements 1\n# length_unit: m\nleg1_slide,x,y,z\n0.1,0,0,0.4\n")
    cases = [
        ["calibrate", "hexaslide_6pus", "--data", str(bad), "--out", str(tmp_path / "o")],
        ["calibrate", "hexaslide_6pus", "--data", str(tmp_path / "none.csv"), "--out", "o"],
        ["calibrate", "no_such_model", "--data", str(bad), "--out", "o"],
        ["compensate", "hexaslide_6pus", "--targets", str(bad), "--out", "c.csv"],
    ]
    for args in cases:
        res = runner.invoke(main, args)
        assert res.exit_code == 1, (args, res.output)
        lines = res.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("pincal: error:"), res.stderr
        assert "Traceback" not in res.output
    res = runner.invoke(main, ["calibrate", "hexaslide_6pus", "--data", str(bad), "--out", "o"])
    assert "missing actuator columns ['leg2_slide'" in res.stderr


def test_too_few_poses_is_refused(tmp_path):
    runner = CliRunner()
    res = runner.invoke(
        main, ["simulate", "hexaslide_6pus", "--random", "5", "--out", str(tmp_path / "m.csv")]
    )
    assert res.exit_code == 0, res.output
    res = runner.invoke(
        main,
        [
            "calibrate",
            "hexaslide_6pus",
            "--data",
            str(tmp_path / "m.csv"),
            "--out",
            str(tmp_path / "o"),
        ],
    )
    assert res.exit_code == 1
    assert "TooFewPosesError" in res.stderr and "at least 9 poses" in res.stderr


def test_simulate_uses_the_actuator_columns_of_a_poses_file(tmp_path):
    """The commands measured are the file's actuator values, not a fresh IK of its poses."""
    mech = load_mechanism("wedge3")
    q = sample_actuators(mech, 4, np.random.default_rng(3))
    poses = [mech.forward(row) for row in q]
    # Rows whose actuator values are shifted from the poses: only the columns can say so.
    shifted = q + 1e-4
    path = tmp_path / "poses.csv"
    write_poses(path, poses, actuated=mech.actuated, q_act=shifted)
    out = tmp_path / "m.csv"
    res = CliRunner().invoke(
        main, ["simulate", "wedge3", "--poses", str(path), "--noise", "0,0", "--out", str(out)]
    )
    assert res.exit_code == 0, res.output
    np.testing.assert_allclose(read_measurements(out, mech).q_act, shifted, atol=1e-12)
