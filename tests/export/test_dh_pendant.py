"""`pincal export --format dh-offsets-lengths`: zero offsets and link lengths on the
nominal DH table, checked by the DH forward kinematics written in the test."""

from __future__ import annotations

import numpy as np
import pytest

from pincal.export import CalibratedMachine, export_calibration
from pincal.io import read_calibration
from pincal.model import load_mechanism, parameters

from ._independent import dh_forward, pose_error, read_yaml_body
from .test_dh import UR5_DH


def _errors(doc: dict, machine: CalibratedMachine, q: np.ndarray) -> np.ndarray:
    ref = machine.reference(q)
    return np.array([pose_error(dh_forward(doc, r), T) for r, T in zip(q, ref, strict=True)])


def test_zero_offsets_are_held_exactly_on_the_nominal_table():
    ur5 = load_mechanism("ur5")
    params = parameters(ur5, "full")
    rng = np.random.default_rng(4)
    values = np.array([rng.uniform(-1e-2, 1e-2) if p.dof == "offset" else 0.0
                       for p in params.parameters])  # fmt: skip
    names = [p.name for p in params.parameters]
    machine = CalibratedMachine.from_mechanisms(
        params.apply(ur5, values), ur5, dict(zip(names, values, strict=True))
    )
    done = export_calibration(machine, "dh-offsets-lengths", poses=40)
    doc = read_yaml_body(done.text)
    rows = doc["rows"]
    offsets = {p.joint: v for p, v in zip(params.parameters, values, strict=True)
               if p.dof == "offset"}  # fmt: skip
    for row in rows:  # the nominal lengths are the published ones, the offsets the errors
        assert row["zero_offset"] == pytest.approx(offsets[row["joint"]], abs=1e-9)
        assert row["alpha"] == row["nominal"]["alpha"]
    assert rows[0]["d"] == pytest.approx(UR5_DH["d1"], abs=1e-9)
    assert abs(rows[1]["a"]) == pytest.approx(UR5_DH["a2"], abs=1e-9)
    errs = _errors(doc, machine, done.projection.q_act)
    assert errs[:, 0].max() < 1e-6 and errs[:, 1].max() < 1e-6
    assert done.projection.position_max < 1e-6


def test_what_offsets_and_lengths_cannot_hold_is_reported(ur5_calibration):
    """The default simulated errors tilt axes and move the base: the pendant's numbers
    keep part of the calibration; the header's figures are the controller's own."""
    machine = CalibratedMachine.from_directory(read_calibration(ur5_calibration))
    done = export_calibration(machine, "dh-offsets-lengths", poses=40)
    doc = read_yaml_body(done.text)
    q = done.projection.q_act
    errs = _errors(doc, machine, q)
    assert np.sqrt(np.mean(errs[:, 0] ** 2)) == pytest.approx(
        done.projection.position_rms, rel=1e-6
    )
    nominal_doc = {**doc, "rows": [{**r, **r["nominal"]} for r in doc["rows"]]}
    plain = _errors(nominal_doc, machine, q)  # the pendant without the calibration
    assert np.sqrt(np.mean(errs[:, 0] ** 2)) < 0.5 * np.sqrt(np.mean(plain[:, 0] ** 2))
    assert any("twists" in s for s in done.projection.not_expressed)
