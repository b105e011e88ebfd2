"""Public-model habits (the open world): small machines written the way many public
closed-loop URDF + robot.yaml files are, under tests/model/machines/."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import pincal
from pincal.model import load_mechanism, parameters, sample_actuators

MACHINES = Path(__file__).parent / "machines"


@pytest.fixture(scope="module")
def fivebar():
    return load_mechanism(MACHINES / "fivebar")


def _fd_identification_jacobian(mech, params, rows, h=1e-6):
    cols = []
    for k in range(len(params)):
        e = np.zeros(len(params))
        e[k] = h
        plus = [params.apply(mech, e).forward(r).translation[:2] for r in rows]
        minus = [params.apply(mech, -e).forward(r).translation[:2] for r in rows]
        cols.append((np.concatenate(plus) - np.concatenate(minus)) / (2 * h))
    return np.stack(cols, axis=1)


# ------------------------------------------------------------- 5. closure frames = joint names
def test_closure_frames_named_by_joints_give_the_fd_identification_jacobian(fivebar):
    assert fivebar.closures[0].frame_a == "pin_l"
    assert fivebar.frame_link("pin_l") == "tip_l" and fivebar.frame_link("end_r") == "tip_r"
    assert np.max(np.abs(fivebar.closure_residual(fivebar.q_home))) < 1e-12
    params = parameters(fivebar, "full")
    home = fivebar.actuators_of(fivebar.q_home)
    rows = home + np.array([[0.0, 0.0], [0.05, -0.04], [-0.03, 0.06]])
    J = pincal.identification_jacobian(fivebar, params, rows)
    J_fd = _fd_identification_jacobian(fivebar, params, rows)
    assert J.shape == (6, len(params))
    assert np.max(np.abs(J - J_fd)) <= 1e-6 * np.max(np.abs(J))


# ------------------------------------------------- 6. <limit effort velocity/> without a range
def test_limit_without_lower_upper_is_unlimited_with_a_note(fivebar):
    assert np.all(np.isinf(fivebar.actuator_limits))
    assert any("'mot_l'" in n and "zero-width" in n and "unlimited" in n for n in fivebar.notes)
    home = fivebar.actuators_of(fivebar.q_home)
    target = fivebar.forward(home + 0.1)
    q_act = fivebar.inverse(target)  # was: "outside its limits [0, 0]"
    assert np.allclose(fivebar.forward(q_act).translation, target.translation, atol=1e-9)
    rows = sample_actuators(fivebar, 12, np.random.default_rng(3))
    assert np.all(np.ptp(rows, axis=0) > 0.3)  # was: every row equal to [0, 0]
    assert len({tuple(np.round(r, 9)) for r in rows}) == 12


def test_zero_width_range_takes_the_sidecar_workspace_range():
    xml = (MACHINES / "fivebar" / "fivebar.urdf").read_text()
    sc = pincal.model.read_sidecar(MACHINES / "fivebar" / "fivebar.yaml")
    sc["workspace"] = {"joints": {"mot_l": [1.5, 2.5]}}
    mech = pincal.Mechanism(xml, sc)
    assert np.allclose(mech.actuator_limits[0], [1.5, 2.5])
    assert np.all(np.isinf(mech.actuator_limits[1]))
    assert any("'mot_l'" in n and "[1.5, 2.5]" in n for n in mech.notes)
