"""Machine style: loops open at q = 0, closed only at the sidecar's home guess
(tests/model/machines/rpr3: planar 3-RPR with a floating platform, 3D closures)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pincal.model import load_mechanism
from tests.open_world import acceptance
from tests.open_world.machines import copy_machine


@pytest.fixture(scope="module")
def model(tmp_path_factory) -> Path:
    # random rows over the whole URDF range [0.05, 0.4] are each reachable from home
    # but not one from the next (forward kinematics fails at pose 15 of 30): a workspace
    workspace = {"joints": {f"leg{i}": [0.17, 0.25] for i in (1, 2, 3)}}
    return copy_machine(tmp_path_factory.mktemp("m"), "rpr3", workspace=workspace)


@pytest.fixture(scope="module")
def mech(model):
    return load_mechanism(model)


def test_loads_although_open_at_zero(mech):
    import pinocchio as pin

    assert np.max(np.abs(mech.closure_residual(pin.neutral(mech.model)))) > 0.1
    assert np.max(np.abs(mech.closure_residual(mech.q_home))) <= 1e-12
    assert mech.mobility == 3


def test_round_trip(mech):
    acceptance.check_round_trip(mech)


@pytest.mark.slow
def test_jacobian_matches_central_differences(mech):
    acceptance.check_jacobian(mech)


@pytest.mark.slow
def test_noise_free_recovery(mech):
    acceptance.check_recovery(mech)


@pytest.mark.slow
def test_simulate_calibrate_compensate(model, tmp_path):
    acceptance.check_cli(model, tmp_path)
