"""`pincal export --format linuxcnc-genhexkins`, checked by genhexkins' own inverse
kinematics written in the test (tests/export/_independent.py), not pincal's model."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.export import CalibratedMachine, export_calibration
from pincal.io import read_calibration
from pincal.model import sample_actuators

from ._independent import genhexkins_inverse, read_hal


def _calibrate(tmp, *extra: str):
    runner = CliRunner()
    meas, cal = tmp / "m.csv", tmp / "cal"
    res = runner.invoke(
        main,
        [
            "simulate",
            "stewart_6ups",
            "--random",
            "40",
            "--noise",
            "0,0",
            "--errors",
            "seed:3",
            "--out",
            str(meas),
        ],
    )
    assert res.exit_code == 0, res.output
    res = runner.invoke(
        main, ["calibrate", "stewart_6ups", "--data", str(meas), "--out", str(cal), *extra]
    )
    assert res.exit_code == 0, res.output
    return cal


@pytest.fixture(scope="module")
def stewart_cal(tmp_path_factory):
    """A calibration of the bundled Stewart whose errors are strut-end points and offsets."""
    return _calibrate(tmp_path_factory.mktemp("hex"))


def _model_poses(cal, n=30, seed=11):
    mech = cal.calibrated()
    q = sample_actuators(mech, n, np.random.default_rng(seed))
    poses = np.array([mech.frame_placement(mech.configuration(r)).homogeneous for r in q])
    return q, poses


def test_genhexkins_inverse_matches_the_calibrated_model(stewart_cal, tmp_path):
    out = tmp_path / "hexapod.hal"
    res = CliRunner().invoke(
        main,
        [
            "export",
            str(stewart_cal),
            "--format",
            "linuxcnc-genhexkins",
            "--out",
            str(out),
            "--poses",
            "40",
        ],
    )
    assert res.exit_code == 0, res.output
    text = out.read_text()
    assert "cannot express: nothing" in res.output and "# cannot express: nothing" in text
    base, plat, off = read_hal(text)
    cal = read_calibration(stewart_cal)
    q, poses = _model_poses(cal)
    err = np.array(
        [genhexkins_inverse(base, plat, off, T) - r for T, r in zip(poses, q, strict=True)]
    )
    assert np.abs(err).max() <= 1e-6
    # the check can fail: the nominal machine's strut ends miss the calibrated one by far more
    nom = cal.nominal()
    qn = nom.configuration(nom.actuators_of(nom.q_home))
    nominal_base = np.array(
        [nom.frame_placement(qn, f"leg{i + 1}_u2").translation for i in range(6)]
    )
    err_nominal = [
        genhexkins_inverse(nominal_base, plat, off, T) - r for T, r in zip(poses, q, strict=True)
    ]
    assert np.abs(err_nominal).max() > 1e-4
    # the header's figures: the controller's forward kinematics (Newton) vs the model
    pos = next(line for line in text.splitlines() if line.startswith("#   position"))
    assert float(pos.split("max ")[1].split(" um")[0]) <= 1.0


def test_actuator_scale_is_named_and_its_residual_reported_honestly(tmp_path):
    """With a gain the struts' length is not reading + offset: named, and the reported
    joint residual is what genhexkins' own inverse gives at the model's poses."""
    cal_dir = _calibrate(tmp_path, "--model", "geometric+gain")
    cal = read_calibration(cal_dir)
    machine = CalibratedMachine.from_directory(cal)
    assert machine.gains()
    done = export_calibration(machine, "linuxcnc-genhexkins", poses=25, seed=2)
    proj = done.projection
    assert any("actuator scale" in s for s in proj.not_expressed)
    base, plat, off = read_hal(done.text)
    poses = machine.reference(proj.q_act)
    err = np.array(
        [genhexkins_inverse(base, plat, off, T) - r for T, r in zip(poses, proj.q_act, strict=True)]
    )
    assert proj.joint_max == pytest.approx(np.abs(err).max(), rel=1e-6, abs=1e-12)
    assert proj.joint_rms == pytest.approx(np.sqrt(np.mean(err**2)), rel=1e-6, abs=1e-12)


def test_genhexkins_refuses_a_serial_arm(tmp_path, ur5_calibration):
    runner = CliRunner()
    cal = ur5_calibration
    out = tmp_path / "x.hal"
    res = runner.invoke(
        main, ["export", str(cal), "--format", "linuxcnc-genhexkins", "--out", str(out)]
    )
    assert res.exit_code == 1 and "ExportError" in res.output and "6 prismatic" in res.output
    assert not out.exists()
    inside = runner.invoke(
        main, ["export", str(cal), "--format", "generic-table", "--out", str(cal / "table.yaml")]
    )
    assert inside.exit_code == 1 and "OutputPathError" in inside.output
