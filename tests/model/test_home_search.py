"""The regular-home search and the floor on a hand-written 3R arm, singular at q = 0."""

from __future__ import annotations

import numpy as np
import pytest

from pincal.model import Mechanism, above_floor, conditioning, load_mechanism, regular_home
from pincal.model.reach._floor import moving_points, point_heights

# a waist about z, a shoulder and an elbow about y; stretched along x at q = 0, where the
# shoulder and elbow both move the tool along z only (rank 2 of 3)
LIMIT = '<limit lower="-3" upper="3" effort="1" velocity="1"/>'
ARM = f"""<robot name="arm3r">
  <link name="base"/><link name="l1"/><link name="l2"/><link name="l3"/><link name="tool"/>
  <joint name="waist" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>{LIMIT}</joint>
  <joint name="shoulder" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0 0 0.2"/><axis xyz="0 1 0"/>{LIMIT}</joint>
  <joint name="elbow" type="revolute"><parent link="l2"/><child link="l3"/>
    <origin xyz="0.4 0 0"/><axis xyz="0 1 0"/>{LIMIT}</joint>
  <joint name="flange" type="fixed"><parent link="l3"/><child link="tool"/>
    <origin xyz="0.3 0 0"/></joint>
</robot>
"""
SIDE = {"measured_frame": "tool", "measured": "position"}
LENGTH = 0.9  # 0.3 + 0.4 + 0.2: tool → elbow → shoulder → waist origins [m]


def arm(side: dict | None = None) -> Mechanism:
    return Mechanism(ARM, {**SIDE, **(side or {})}, name="arm3r")


def fd_sigma(mech: Mechanism, q_act: np.ndarray, h: float = 1e-6) -> float:
    """σ_min of the finite-difference tool-position Jacobian over the chain length."""

    def tip(q: np.ndarray) -> np.ndarray:
        return mech.frame_placement(mech.with_actuators(mech.q_home, q)).translation

    cols = [(tip(q_act + h * e) - tip(q_act - h * e)) / (2 * h) for e in np.eye(q_act.size)]
    return float(np.linalg.svd(np.array(cols).T / LENGTH, compute_uv=False).min())


def test_conditioning_is_the_scaled_jacobian_smallest_singular_value():
    mech = arm()
    assert conditioning(mech, mech.q_home) < 1e-12  # singular at q = 0
    rng = np.random.default_rng(3)
    for _ in range(3):
        q_act = rng.uniform(-1.5, 1.5, 3)
        got = conditioning(mech, mech.with_actuators(mech.q_home, q_act))
        assert got == pytest.approx(fd_sigma(mech, q_act), rel=1e-6)


def test_regular_home_is_regular_near_zero_on_the_lattice_and_deterministic():
    mech = arm()
    ranges = np.array(mech.actuator_limits)
    found = regular_home(mech, ranges, None)
    assert found.sigma_start == 0.0
    assert found.sigma == pytest.approx(fd_sigma(mech, found.q_act), rel=1e-6)
    assert found.sigma > 0.1
    steps = found.q_act / (np.pi / 12)
    assert np.allclose(steps, np.round(steps)) and np.all(np.abs(steps) <= 6)
    assert np.array_equal(regular_home(mech, ranges, None).q_act, found.q_act)
    # a narrower elbow range is respected
    ranges[2] = [0.5, 1.2]
    narrow = regular_home(mech, ranges, None)
    assert 0.5 <= narrow.q_act[2] <= 1.2 and narrow.sigma > 0.05


def test_regular_home_keeps_the_moving_points_above_a_floor():
    mech = arm()
    points = moving_points(mech)
    names = {mech.model.frames[int(f)].name for f in points}
    assert "tool" in names and "l1" not in names  # the waist's origin does not move
    found = regular_home(mech, np.array(mech.actuator_limits), 0.32)  # home q = 0 is at 0.3
    q = mech.with_actuators(mech.q_home, found.q_act)
    assert point_heights(mech, q, points).min() >= 0.32 and found.sigma > 0.05
    floored = arm({"workspace": {"floor": 0.32}})
    assert floored.workspace.floor == 0.32
    assert above_floor(floored, np.array([found.q_act, np.zeros(3)])).tolist() == [True, False]
    assert above_floor(arm(), np.zeros((1, 3))).tolist() == [True]  # no floor: no check


def test_a_urdf_file_keeps_its_zero_home_and_has_no_floor(tmp_path):
    (tmp_path / "arm3r.urdf").write_text(ARM)
    mech = load_mechanism(tmp_path / "arm3r.urdf", "tool")
    assert np.allclose(mech.q_home, 0.0) and mech.workspace.floor is None
