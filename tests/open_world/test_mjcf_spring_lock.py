"""Machine style: an MJCF leg whose foot hangs on a spring joint (``stiffness``) — the
four-bar of machines.mjcf_fourbar_straight with a toe hinged to its coupler, the measured
site on the toe. The spring joint is reported; ``lock:`` in the sidecar beside the MJCF
(the key of robots by name) makes it fixed (issue 28, cause 6)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml

from pincal.errors import MobilityError, ModelFileError, UnknownNameError
from pincal.model import load_mechanism, load_mjcf
from tests.open_world import acceptance
from tests.open_world.roster import mjcf_toe_leg


def _write(folder: Path, sidecar: dict | None) -> Path:
    path = folder / "toe_leg.xml"
    path.write_text(mjcf_toe_leg(), encoding="utf-8")
    if sidecar is not None:
        path.with_suffix(".yaml").write_text(yaml.safe_dump(sidecar), encoding="utf-8")
    return path


def _tool_at_toe(mech, toe: float) -> np.ndarray:
    """World position [m] of the site ``tool`` of the unlocked leg (measured at the
    coupler) with the four-bar closed at crank −0.3 rad and the toe set to ``toe`` [rad]."""
    q = mech.configuration(np.array([-0.3]))
    q[mech.model.joints[mech.model.getJointId("toe_joint")].idx_q] = toe
    data = mech.model.createData()
    pin.framesForwardKinematics(mech.model, data, q)
    return data.oMf[mech.model.getFrameId("tool")].translation.copy()


def test_a_free_spring_joint_is_refused_with_the_way_to_lock_it(tmp_path):
    """Measured on the toe, the spring joint is a passive dof nothing fixes."""
    with pytest.raises(MobilityError, match="free passive joints: \\['toe_joint'\\]") as err:
        load_mjcf(_write(tmp_path, {"measured_frame": "tool", "measured": "position"}))
    assert "'toe_joint': a spring joint (MJCF stiffness)" in str(err.value)
    assert "'lock: {toe_joint: home}'" in str(err.value) and "keyframe" not in str(err.value)


def test_a_spring_joint_that_does_not_move_the_measured_frame_is_reported(tmp_path):
    mech = load_mjcf(_write(tmp_path, {"measured_frame": "coupler"}))
    assert "toe_joint" in list(mech.model.names)
    said = [n for n in mech.notes if "'toe_joint' has a spring (MJCF stiffness 5)" in n]
    assert said and "lock: {joint: value or home}" in said[0]


@pytest.mark.parametrize("value", [0.2, "home"])
def test_lock_in_the_sidecar_fixes_the_spring_joint(tmp_path, value):
    free = load_mjcf(_write(tmp_path, {"measured_frame": "coupler"}))
    side = {"measured_frame": "tool", "measured": "position", "lock": {"toe_joint": value}}
    mech = load_mechanism(_write(tmp_path, side))  # load_mechanism reads MJCF too
    assert "toe_joint" not in list(mech.model.names) and mech.actuated == ("crank_joint",)
    held = 0.0 if value == "home" else 0.2  # home: the keyframe's toe value
    assert any(f"toe_joint = {held:g} (a spring, MJCF stiffness 5)" in n for n in mech.notes)
    assert not any("'toe_joint' has a spring" in n for n in mech.notes)
    assert any("'rocker_joint' has a spring" in n for n in mech.notes)  # not locked
    got = mech.forward(np.array([-0.3])).translation
    assert np.max(np.abs(got - _tool_at_toe(free, held))) <= 1e-12
    assert np.max(np.abs(got - _tool_at_toe(free, held + 0.1))) > 1e-3  # the toe matters


def test_the_locked_leg_calibrates(tmp_path):
    side = {"measured_frame": "tool", "measured": "position", "lock": {"toe_joint": 0}}
    acceptance.check_recovery(load_mjcf(_write(tmp_path, side)))


def test_lock_errors_name_the_joint_and_the_valid_values(tmp_path):
    with pytest.raises(UnknownNameError, match="tow_joint"):
        load_mjcf(_write(tmp_path, {"lock": {"tow_joint": 0}}))
    with pytest.raises(ModelFileError, match="finite number or 'home'"):
        load_mjcf(_write(tmp_path, {"lock": {"toe_joint": "zero"}}))


def test_lock_on_the_command_line_of_an_mjcf_points_to_its_sidecar(tmp_path):
    from click.testing import CliRunner

    from pincal.cli import main

    path = _write(tmp_path, {"measured_frame": "tool", "measured": "position"})
    res = CliRunner().invoke(main, ["info", str(path), "--lock", "toe_joint=0"])
    assert res.exit_code != 0
    assert "(e.g. 'lock: {joint: 0}') in the sidecar <stem>.yaml beside the MJCF" in res.output


def test_load_mjcf_takes_lock_as_an_argument(tmp_path):
    path = _write(tmp_path, {"measured_frame": "tool", "measured": "position"})
    mech = load_mjcf(path, lock={"toe_joint": 0.2})
    assert "toe_joint" not in list(mech.model.names)
    assert any("toe_joint = 0.2 (a spring, MJCF stiffness 5)" in n for n in mech.notes)
