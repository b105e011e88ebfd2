"""Linear-delta exports (Klipper printer.cfg, LinuxCNC lineardeltakins), checked by the
controllers' documented equations written in the test (tests/export/_independent_delta.py)
on a linear delta written for the purpose (tests/open_world/linear_delta.py)."""

from __future__ import annotations

import re

import numpy as np
import pinocchio as pin
import pytest

from pincal.errors import ExportError
from pincal.export import FORMATS, CalibratedMachine, export_calibration
from pincal.model import Mechanism, load_mechanism, sample_actuators
from tests.open_world.linear_delta import ANGLES, EFFECTOR_R, RANGE, TOWER_R, linear_delta

from ._independent_delta import (
    klipper_forward,
    lineardeltakins_forward,
    read_klipper,
    read_lineardeltakins,
)


@pytest.fixture(scope="module")
def nominal() -> Mechanism:
    urdf, sidecar = linear_delta()
    return Mechanism(urdf, sidecar, name="linear_delta")


def _moved(mech: Mechanism, tilt_rod: float = 0.0) -> Mechanism:
    """Tower 1 moved 3 mrad round the circle, carriage 2's zero 0.8 mm higher, tower 3's
    rods 0.5 mm longer (all a Klipper delta holds); ``tilt_rod``: one rod of tower 1
    longer by that much [m] (a parallelogram that is not one: no delta equation holds it).

    Tower 1 moves parallel to itself (its rods stay parallel to the effector's anchors),
    so that its effective point ``carriage − effector anchor`` keeps the radius
    ``TOWER_R − EFFECTOR_R`` at the angle 210° + 3 mrad.
    """
    joints = mech.tree.joints
    up = np.array([0.0, 0.0, 1.0])
    a, e = ANGLES[0], 3e-3
    o1, o2 = joints["carriage1"].origin, joints["carriage2"].origin
    moved = (TOWER_R - EFFECTOR_R) * np.array([np.cos(a + e), np.sin(a + e), 0.0])
    moved += EFFECTOR_R * np.array([np.cos(a), np.sin(a), 0.0]) + o1.translation[2] * up
    origins = {
        "carriage1": pin.SE3(o1.rotation, moved),
        "carriage2": pin.SE3(o2.rotation, o2.translation + 0.8e-3 * up),
    }
    for side in "ab":
        o = joints[f"tip3{side}_joint"].origin
        origins[f"tip3{side}_joint"] = pin.SE3(o.rotation, o.translation + 0.5e-3 * up)
    if tilt_rod:
        o = joints["tip1a_joint"].origin
        origins["tip1a_joint"] = pin.SE3(o.rotation, o.translation + tilt_rod * up)
    return mech.with_joint_origins(origins)


def _model_points(mech: Mechanism, q: np.ndarray) -> np.ndarray:
    return np.array([mech.frame_placement(mech.configuration(r)).translation for r in q]) * 1e3


def _errors(mech: Mechanism, q: np.ndarray, controller) -> np.ndarray:
    """|controller − model| [mm] per reading row."""
    ctl = np.array([controller(r) for r in q])
    return np.linalg.norm(ctl - _model_points(mech, q), axis=1)


def test_klipper_export_reproduces_the_calibration(nominal):
    cal = _moved(nominal)
    exp = export_calibration(
        CalibratedMachine.from_mechanisms(cal, nominal), "klipper-delta", poses=60
    )
    cfg = read_klipper(exp.text)
    q = sample_actuators(cal, 40, np.random.default_rng(5))
    top = np.full(3, RANGE[1] * 1e3)  # the endstops: the top of each carriage's range
    err = _errors(cal, q, lambda r: klipper_forward(cfg, r * 1e3, top))
    assert err.max() < 1e-3  # ≤ 1 µm
    assert exp.projection.position_max < 1e-6 and "nothing" in exp.text
    # the calibration matters: the nominal model is far from it at the same readings
    assert np.linalg.norm(_model_points(nominal, q) - _model_points(cal, q), axis=1).max() > 0.1
    angles = [st["angle"] for st in cfg["steppers"]]
    assert angles[0] == pytest.approx(210.0 + np.degrees(3e-3), abs=1e-6)
    assert cfg["steppers"][2]["arm_length"] - cfg["steppers"][0]["arm_length"] == pytest.approx(
        0.5, abs=1e-6
    )


def test_lineardeltakins_reports_what_one_radius_and_one_rod_cannot_hold(nominal):
    cal = _moved(nominal)
    exp = export_calibration(
        CalibratedMachine.from_mechanisms(cal, nominal), "linuxcnc-lineardeltakins", poses=60
    )
    R, L = read_lineardeltakins(exp.text)
    homes = {
        int(j): (name, float(h))
        for j, name, h in re.findall(
            r"^# joint\.(\d) = (\w+): .* HOME_OFFSET (\S+)$", exp.text, re.M
        )
    }
    q = sample_actuators(cal, 40, np.random.default_rng(6))
    col = {n: k for k, n in enumerate(cal.actuated)}

    def controller(r: np.ndarray) -> np.ndarray:
        joints = [homes[j][1] - (RANGE[1] - r[col[homes[j][0]]]) * 1e3 for j in range(3)]
        return lineardeltakins_forward(R, L, np.array(joints))

    err = _errors(cal, q, controller)
    rms = float(np.sqrt(np.mean(err**2)))
    assert rms > 0.01  # per-tower rods and angles do not fit one R and one L
    assert rms == pytest.approx(exp.projection.position_rms * 1e3, rel=0.3)
    assert "rod lengths differ" in exp.text and "tower angles" in exp.text
    exact = export_calibration(
        CalibratedMachine.from_mechanisms(nominal, nominal), "linuxcnc-lineardeltakins", poses=60
    )
    assert exact.projection.position_max < 1e-6


def test_a_parallelogram_that_is_not_one_is_reported(nominal):
    cal = _moved(nominal, tilt_rod=1e-3)
    exp = export_calibration(
        CalibratedMachine.from_mechanisms(cal, nominal), "klipper-delta", poses=60
    )
    assert exp.projection.position_rms > 1e-6
    assert "not vertical lines with rigid rods" in exp.text
    cfg = read_klipper(exp.text)
    q = sample_actuators(cal, 40, np.random.default_rng(7))
    err = _errors(cal, q, lambda r: klipper_forward(cfg, r * 1e3, np.full(3, RANGE[1] * 1e3)))
    assert float(np.sqrt(np.mean(err**2))) == pytest.approx(
        exp.projection.position_rms * 1e3, rel=0.3
    )


def test_a_machine_that_is_not_a_linear_delta_is_refused():
    stewart = load_mechanism("stewart_6ups")
    machine = CalibratedMachine.from_mechanisms(stewart, stewart)
    with pytest.raises(ExportError, match="three prismatic"):
        FORMATS["klipper-delta"].build(machine, np.zeros((1, 6)))
