"""Machine style: closure frames named by URDF joints (tests/model/machines/fivebar:
``closed_loop: [[pin_l, end_r]]`` names joints, not links; planar 2-dof, measured x y).

Its actuators have no range (``<limit effort velocity/>``), so the copy under test gets
a sidecar workspace around home (see test_limits_without_range.py for the unlimited
machine as written)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pincal.model import load_mechanism
from tests.open_world import acceptance
from tests.open_world.machines import FIVEBAR_WORKSPACE, copy_machine


@pytest.fixture(scope="module")
def model(tmp_path_factory) -> Path:
    return copy_machine(tmp_path_factory.mktemp("m"), "fivebar", workspace=FIVEBAR_WORKSPACE)


@pytest.fixture(scope="module")
def mech(model):
    return load_mechanism(model)


def test_loads_with_joint_named_closure_frames(mech):
    assert (mech.closures[0].frame_a, mech.closures[0].frame_b) == ("pin_l", "end_r")
    assert np.max(np.abs(mech.closure_residual(mech.q_home))) <= 1e-12


def test_round_trip(mech):
    acceptance.check_round_trip(mech)


def test_jacobian_matches_central_differences(mech):
    acceptance.check_jacobian(mech)


def test_noise_free_recovery(mech):
    acceptance.check_recovery(mech)


def test_simulate_calibrate_compensate(model, tmp_path):
    acceptance.check_cli(model, tmp_path)
