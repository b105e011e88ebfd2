"""Reduced-mobility compensation: the components a machine controls, and why not more."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.compensation import compensate, compensation_components
from pincal.errors import MeasurementError, MobilityError
from pincal.io import read_commands, write_poses
from pincal.model import Mechanism, load_mechanism, parameters, sample_actuators


@pytest.fixture(scope="module")
def wedge():
    return load_mechanism("wedge3")


@pytest.fixture(scope="module")
def wedge_as_pose(wedge):
    """wedge3 declared as measuring the full pose: 6 components on a 3-DOF machine."""
    return Mechanism(wedge.urdf_xml, wedge.sidecar.replace(measured="pose"), name="wedge_pose")


def test_default_components_are_the_measured_ones(wedge):
    assert compensation_components(wedge) == ("x", "z", "ry")
    assert compensation_components(wedge, "z, x") == ("x", "z")
    with pytest.raises(MeasurementError, match="invalid"):
        compensation_components(wedge, "x,q")


def test_too_many_components_say_why(wedge_as_pose):
    with pytest.raises(MobilityError, match="3 degrees of freedom.*6.*at most 3"):
        compensate(wedge_as_pose, [pin.SE3.Identity()])


def test_chosen_components_are_reached_on_a_3dof_machine(wedge, wedge_as_pose):
    params = parameters(wedge, "patent")
    cal = params.apply(wedge_as_pose, np.full(len(params), 3e-4))
    q = sample_actuators(wedge, 5, np.random.default_rng(1))
    targets = [wedge.forward(row) for row in q]
    res = compensate(cal, targets, components=["x", "z", "ry"])
    assert res.components == ("x", "z", "ry") and not res.unreachable
    for T, row in zip(targets, res.commands, strict=True):
        got = cal.forward(row)
        np.testing.assert_allclose(got.translation[[0, 2]], T.translation[[0, 2]], atol=1e-9)
        np.testing.assert_allclose(pin.log3(T.rotation.T @ got.rotation)[1], 0.0, atol=1e-9)
    assert np.abs(res.commands - q).max() > 1e-5  # the calibration changed the commands


def test_unreachable_targets_say_why(wedge):
    far = pin.SE3(np.eye(3), np.array([5.0, 0.0, 5.0]))
    res = compensate(wedge, [far])
    assert res.unreachable == (0,)
    assert "imposing x z ry" in res.reasons[0] and "unreachable" in res.reasons[0]


def test_cli_target_file_with_only_controlled_columns(tmp_path, wedge):
    q = sample_actuators(wedge, 3, np.random.default_rng(2))
    full = write_poses(tmp_path / "full.csv", [wedge.forward(r) for r in q])
    lines = full.read_text().splitlines()
    cols = lines[4].split(",")
    keep = [cols.index(c) for c in ("x", "z", "ry")]
    sub = lines[:4] + [",".join(line.split(",")[k] for k in keep) for line in lines[4:]]
    (tmp_path / "t.csv").write_text("\n".join(sub) + "\n")
    out = tmp_path / "c.csv"
    res = CliRunner().invoke(
        main, ["compensate", "wedge3", "--targets", str(tmp_path / "t.csv"), "--out", str(out)]
    )
    assert res.exit_code == 0, res.output
    assert "compensating x z ry" in res.output
    np.testing.assert_allclose(read_commands(out, wedge)[1], q, atol=1e-9)
    res = CliRunner().invoke(
        main, ["compensate", "wedge3", "--targets", str(tmp_path / "t.csv"),
               "--components", "x,y,z", "--out", str(out)],
    )  # fmt: skip
    assert res.exit_code == 1
    assert "gives x z ry" in res.stderr and len(res.stderr.strip().splitlines()) == 1
