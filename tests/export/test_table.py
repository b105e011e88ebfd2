"""`pincal export --format generic-table`, checked by the table's equation (1) written
in the test: a chain of ``Tr(xyz) Rot(rpy) Motion(axis, scale q + zero_offset)``."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.export import CalibratedMachine, export_calibration
from pincal.io import read_calibration
from pincal.model import load_mechanism, parameters

from ._independent import pose_error, read_yaml_body, table_forward


def _check(machine: CalibratedMachine, done) -> None:
    doc = read_yaml_body(done.text)
    link = machine.calibrated.frame_link(machine.calibrated.measured_frame)
    ref = machine.reference(done.projection.q_act)
    errs = np.array(
        [
            pose_error(table_forward(doc, r, link), T)
            for r, T in zip(done.projection.q_act, ref, strict=True)
        ]
    )
    assert errs[:, 0].max() <= 1e-6 and errs[:, 1].max() <= 1e-6
    assert done.projection.position_max <= 1e-6


def test_table_of_a_ur5_calibration(tmp_path, ur5_calibration):
    runner = CliRunner()
    cal = ur5_calibration
    out = tmp_path / "ur5.yaml"
    res = runner.invoke(
        main,
        [
            "export",
            str(cal),
            "--format",
            "generic-table",
            "--out",
            str(out),
            "--poses",
            "20",
            "--json",
        ],
    )
    assert res.exit_code == 0, res.output
    machine = CalibratedMachine.from_directory(read_calibration(cal))
    done = export_calibration(machine, "generic-table", poses=20)
    assert done.text == out.read_text()
    doc = read_yaml_body(done.text)
    # the offsets are the calibration's, the nominal placements the nominal URDF's
    for row in doc["actuated"]:
        assert row["zero_offset"] == pytest.approx(machine.offset(row["joint"]), abs=1e-12)
    nominal = {j["name"]: j["nominal"]["xyz"] for j in doc["joints"]}
    assert nominal["elbow_joint"] == pytest.approx([0.0, -0.1197, 0.425], abs=1e-12)
    _check(machine, done)


def test_table_holds_a_gain_as_scale():
    ur5 = load_mechanism("ur5")
    params = parameters(ur5, "full")
    rng = np.random.default_rng(3)
    values = rng.uniform(-1e-3, 1e-3, len(params))
    names = {p.name: v for p, v in zip(params.parameters, values, strict=True)}
    names["elbow_joint.gain"] = 2e-3
    machine = CalibratedMachine.from_mechanisms(params.apply(ur5, values), ur5, names)
    done = export_calibration(machine, "generic-table", poses=15, seed=4)
    doc = read_yaml_body(done.text)
    assert [a.get("scale") for a in doc["actuated"] if a["joint"] == "elbow_joint"] == [1.002]
    _check(machine, done)
    # the check can fail: without the scale the table's chain misses by far more
    for a in doc["actuated"]:
        a.pop("scale", None)
    link = machine.calibrated.frame_link(machine.calibrated.measured_frame)
    ref = machine.reference(done.projection.q_act)
    worst = max(
        pose_error(table_forward(doc, r, link), T)[0]
        for r, T in zip(done.projection.q_act, ref, strict=True)
    )
    assert worst > 1e-5
    # a DH table cannot hold the gain: it says so
    dh = export_calibration(machine, "dh-standard", poses=15, seed=4)
    assert any("elbow_joint.gain" in s for s in dh.projection.not_expressed)
