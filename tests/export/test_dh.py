"""`pincal export --format dh-standard|dh-modified` on UR5, checked by DH forward
kinematics written in the test from the published formulas."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.export import CalibratedMachine, export_calibration
from pincal.io import read_calibration
from pincal.model import load_mechanism, parameters, sample_actuators

from ._independent import dh_forward, pose_error, read_yaml_body

#: the published UR5 DH lengths [m] (Universal Robots): d1, a2, a3, d4, d5, d6
UR5_DH = {"d1": 0.089159, "a2": 0.425, "a3": 0.39225, "d4": 0.10915, "d5": 0.09465, "d6": 0.0823}


@pytest.fixture(scope="module")
def ur5():
    return load_mechanism("ur5")


def _dh_expressible(
    ur5, seed=4, parallel=("shoulder_lift_joint", "elbow_joint", "wrist_1_joint")
) -> CalibratedMachine:
    """An arm (UR5 by default) with errors DH can hold: joint-origin translations, zero
    offsets and the tilts of the axes that have no parallel neighbour (``parallel``: the
    axes that stay parallel, UR5's 2-3-4)."""
    params = parameters(ur5, "full")
    rng = np.random.default_rng(seed)
    values = np.zeros(len(params))
    for k, p in enumerate(params.parameters):
        if p.dof in ("tx", "ty", "tz"):
            values[k] = rng.uniform(-1e-3, 1e-3)
        elif p.dof == "offset" or p.joint not in parallel:
            values[k] = rng.uniform(-1e-2, 1e-2)
    names = [p.name for p in params.parameters]
    return CalibratedMachine.from_mechanisms(
        params.apply(ur5, values), ur5, dict(zip(names, values, strict=True))
    )


@pytest.mark.parametrize("fmt", ["dh-standard", "dh-modified"])
def test_dh_forward_kinematics_matches_the_calibrated_ur5(ur5, fmt):
    machine = _dh_expressible(ur5)
    done = export_calibration(machine, fmt, poses=20, seed=1)
    doc = read_yaml_body(done.text)
    mech = machine.calibrated
    q = sample_actuators(mech, 40, np.random.default_rng(9))
    worst = np.max(
        [
            pose_error(dh_forward(doc, r), mech.frame_placement(mech.configuration(r)).homogeneous)
            for r in q
        ],
        axis=0,
    )
    assert worst[0] <= 1e-6 and worst[1] <= 1e-6
    assert done.projection.position_max <= 1e-6 and done.projection.orientation_max <= 1e-6
    assert not [s for s in done.projection.not_expressed if "tilt" in s]
    # the nominal table beside it has the published UR5 lengths (signs per x-axis choice;
    # modified: frame 0 = frame 1, so d1 is in the base transform)
    lengths = sorted(
        abs(v)
        for row in doc["rows"]
        for k, v in row["nominal"].items()
        if k in ("a", "d") and abs(v) > 1e-9
    )
    expected = [v for k, v in UR5_DH.items() if fmt == "dh-standard" or k != "d1"]
    assert lengths == pytest.approx(sorted(expected), abs=1e-9)


def test_a_tilt_of_parallel_axes_is_named_and_its_residual_reported(tmp_path, ur5_calibration):
    """A full calibration tilts the parallel 2-3-4 axes: DH (parallel convention) cannot
    hold it; the reported residual is what the table's own kinematics gives."""
    runner = CliRunner()
    cal = ur5_calibration
    out = tmp_path / "ur5_dh.yaml"
    res = runner.invoke(
        main,
        [
            "export",
            str(cal),
            "--format",
            "dh-standard",
            "--out",
            str(out),
            "--poses",
            "30",
            "--seed",
            "5",
        ],
    )
    assert res.exit_code == 0, res.output
    assert "parallel convention" in res.output and "tilt" in out.read_text()
    machine = CalibratedMachine.from_directory(read_calibration(cal))
    done = export_calibration(machine, "dh-standard", poses=30, seed=5)
    assert done.text == out.read_text()
    doc = read_yaml_body(done.text)
    ref = machine.reference(done.projection.q_act)
    errs = np.array(
        [pose_error(dh_forward(doc, r), T) for r, T in zip(done.projection.q_act, ref, strict=True)]
    )
    assert done.projection.position_max == pytest.approx(errs[:, 0].max(), rel=1e-6)
    assert done.projection.orientation_max == pytest.approx(errs[:, 1].max(), rel=1e-6)
    assert done.projection.position_max > 1e-4  # a real loss, not rounding


@pytest.mark.parametrize("fmt", ["dh-standard", "dh-modified", "dh-offsets-lengths"])
def test_kinova_tables_are_the_controllers_own_kinematics(fmt):
    """A Kinova arm (Jaco 2: axes 2 and 3 parallel): errors DH holds are written to
    ≤ 1 µm / 1 µrad, and every table's reported figures are its own forward
    kinematics' (written in the test) against the calibrated model."""
    kinova = load_mechanism("kinova")
    parallel = ("j2s6s200_joint_2", "j2s6s200_joint_3")
    machine = _dh_expressible(kinova, seed=6, parallel=parallel)
    done = export_calibration(machine, fmt, poses=20, seed=1)
    doc = read_yaml_body(done.text)
    ref = machine.reference(done.projection.q_act)
    errs = np.array(
        [pose_error(dh_forward(doc, r), T) for r, T in zip(done.projection.q_act, ref, strict=True)]
    )
    assert done.projection.position_max == pytest.approx(errs[:, 0].max(), rel=1e-6, abs=1e-12)
    if fmt != "dh-offsets-lengths":  # a full DH table holds these errors
        assert errs[:, 0].max() <= 1e-6 and errs[:, 1].max() <= 1e-6
    else:  # the pendant's table keeps the nominal twists: the tilts are named, and lost
        assert any("twists" in t for t in done.projection.not_expressed)
        assert errs[:, 0].max() > 1e-5
