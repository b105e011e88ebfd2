"""`rotary-delta` export, checked by the table's equations written in the test
(tests/export/_independent_delta.py) on the open-world Delta with spherical rod ends."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
import yaml

from pincal.export import CalibratedMachine, export_calibration
from pincal.model import Mechanism, sample_actuators
from tests.open_world.first_machines import delta_elbows

from ._independent_delta import rotary_delta_forward


@pytest.fixture(scope="module")
def nominal() -> Mechanism:
    urdf, sidecar = delta_elbows("spherical")
    return Mechanism(urdf, sidecar, name="delta")


def _moved(mech: Mechanism, one_rod: float = 0.0) -> Mechanism:
    """Arm 1's upper arm 0.5 mm longer and its shoulder 0.3 mm higher, arm 2's zero
    2 mrad off, arm 3's rods 0.4 mm longer (all in the table); ``one_rod``: one rod of
    arm 1 longer by that much [m] (the effector tilts: not in the table)."""
    joints = mech.tree.joints
    x, z = np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0])
    o = joints["hinge1"].origin
    origins = {"hinge1": pin.SE3(o.rotation, o.translation + 0.3e-3 * z)}
    for side in "ab":
        e = joints[f"elbow1{side}"].origin
        origins[f"elbow1{side}"] = pin.SE3(e.rotation, e.translation + 0.5e-3 * x)
        t = joints[f"tip3{side}_joint"].origin
        origins[f"tip3{side}_joint"] = pin.SE3(t.rotation, t.translation + 0.4e-3 * z)
    o2 = joints["hinge2"].origin
    origins["hinge2"] = pin.SE3(o2.rotation @ pin.exp3(np.array([0.0, 2e-3, 0.0])), o2.translation)
    if one_rod:
        t = joints["tip1a_joint"].origin
        origins["tip1a_joint"] = pin.SE3(t.rotation, t.translation + one_rod * z)
    return mech.with_joint_origins(origins)


def _errors(mech: Mechanism, doc: dict, q: np.ndarray) -> np.ndarray:
    model = np.array([mech.frame_placement(mech.configuration(r)).translation for r in q]) * 1e3
    ctl = np.array([rotary_delta_forward(doc, r) for r in q])
    return np.linalg.norm(ctl - model, axis=1)


def _doc(text: str) -> dict:
    return yaml.safe_load(text)


def test_rotary_delta_export_reproduces_the_calibration(nominal):
    cal = _moved(nominal)
    exp = export_calibration(
        CalibratedMachine.from_mechanisms(cal, nominal), "rotary-delta", poses=60
    )
    doc = _doc(exp.text)
    q = sample_actuators(cal, 30, np.random.default_rng(3))
    assert _errors(cal, doc, q).max() < 1e-3  # ≤ 1 µm
    assert exp.projection.position_max < 1e-6
    assert _errors(nominal, doc, q).max() > 0.1  # the calibration is in the numbers
    arm1, arm2 = doc["arms"][0], doc["arms"][1]
    assert arm1["upper_arm_mm"] == pytest.approx(250.5, abs=1e-6)
    assert arm1["height_mm"] == pytest.approx(-20.0 + 0.3, abs=1e-6)
    assert arm2["zero_deg"] - 30.0 == pytest.approx(np.degrees(2e-3), abs=1e-6)
    assert "arms differ by" in exp.text  # what a symmetric controller would lose


def test_an_effector_that_tilts_is_reported(nominal):
    cal = _moved(nominal, one_rod=1e-3)
    exp = export_calibration(
        CalibratedMachine.from_mechanisms(cal, nominal), "rotary-delta", poses=60
    )
    assert exp.projection.position_rms > 1e-6 and "not of the form" in exp.text
    q = sample_actuators(cal, 30, np.random.default_rng(4))
    rms = float(np.sqrt(np.mean(_errors(cal, _doc(exp.text), q) ** 2)))
    assert rms == pytest.approx(exp.projection.position_rms * 1e3, rel=0.3)
