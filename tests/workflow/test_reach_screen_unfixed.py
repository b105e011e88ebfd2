"""The reach screen of ``pincal poses`` on a machine whose measured components do not
fix its commands (issue 36): a two-motor neck measured by its roll angle alone.

Before: the screen "compensated" each candidate by imposing rx only, which any of a
line of commands reaches, so it kept every candidate and said nothing. It is now off,
and one line says which components to measure. Measured [rx, ry], the same neck keeps
the screen.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from pincal.errors import MeasurementError
from pincal.model import COMPONENTS, actuator_jacobian, load_mechanism
from pincal.sensitivity import parameters
from pincal.workflow import compensation_test, unfixed_commands
from tests.open_world import linkage_machines as lm


def _neck(folder, measured):
    sidecar = {**lm.NECK_SIDECAR, "measured": measured}
    return load_mechanism(lm.write_mjcf(folder, "neck", lm.mjcf_neck(), sidecar))


def test_screen_is_off_and_says_what_to_measure(tmp_path):
    mech = _neck(tmp_path, ["rx"])
    lines: list[str] = []
    test = compensation_test(mech, parameters(mech, "full"), (1.0, 10.0), 0, say=lines.append)
    assert test is None
    assert len(lines) == 1 and "\n" not in lines[0]
    assert "reach screen off" in lines[0] and "fix only 1 of the 2 commands" in lines[0]
    assert "measure [rx, ry]" in lines[0]
    assert unfixed_commands(mech) in lines[0]


def test_screen_stays_on_when_the_components_fix_the_commands(tmp_path):
    mech = _neck(tmp_path, ["rx", "ry"])
    assert unfixed_commands(mech) == ""
    lines: list[str] = []
    test = compensation_test(mech, parameters(mech, "full"), (1.0, 10.0), 0, say=lines.append)
    assert callable(test) and not any("off" in line for line in lines)


def test_actuator_jacobian_of_chosen_components_matches_finite_differences(tmp_path):
    mech = _neck(tmp_path, ["rx", "ry"])
    q = mech.q_home
    a0 = mech.actuators_of(q)
    G = actuator_jacobian(mech, q, components=COMPONENTS)
    assert G.shape == (6, 2)
    assert np.array_equal(actuator_jacobian(mech, q, components=["ry", "rx"]), G[[4, 3]])
    T0 = mech.forward(a0)
    h = 1e-6
    for k in range(2):
        d = np.zeros(2)
        d[k] = h
        Tp, Tm = mech.forward(a0 + d), mech.forward(a0 - d)
        dp = (Tp.translation - Tm.translation) / (2 * h)
        dr = (pin.log3(T0.rotation.T @ Tp.rotation) - pin.log3(T0.rotation.T @ Tm.rotation)) / (
            2 * h
        )
        assert np.max(np.abs(G[:, k] - np.r_[dp, dr])) <= 1e-6 * max(1.0, np.abs(G).max())


def test_actuator_jacobian_refuses_unknown_components(tmp_path):
    mech = _neck(tmp_path, ["rx", "ry"])
    with pytest.raises(MeasurementError, match=r"components \['yaw'\] unknown"):
        actuator_jacobian(mech, mech.q_home, components=["rx", "yaw"])


def test_a_redundant_arm_measured_in_full_pose_is_screened():
    """A Panda (7 joints, 6 components): its self-motion no measurement fixes, so the
    screen runs (unscreened, its designed poses failed 37 of 1 200 further compensations)."""
    assert unfixed_commands(load_mechanism("panda")) == ""
