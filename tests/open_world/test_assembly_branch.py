"""Machine style: a 3-PRS whose slide range contains a second assembly branch
(tests/model/machines/prs3: knees up at home, knees down reachable in the same range;
forward kinematics and calibration stay on home's branch)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pincal.model import load_mechanism
from tests.open_world import acceptance
from tests.open_world.machines import MODEL_MACHINES, copy_machine


@pytest.fixture(scope="module")
def model(tmp_path_factory) -> Path:
    # the sidecar range [0.1, 0.3] contains the other branch: rows drawn in it are
    # not all reachable one from the next on home's branch; the copy gets a smaller one
    workspace = {"joints": {f"slide{i}": [0.17, 0.23] for i in (1, 2, 3)}}
    return copy_machine(tmp_path_factory.mktemp("m"), "prs3", workspace=workspace)


@pytest.fixture(scope="module")
def mech(model):
    return load_mechanism(model)


@pytest.mark.slow
def test_sampled_poses_stay_on_the_home_branch():
    from pincal.model import sample_actuators

    mech = load_mechanism(MODEL_MACHINES / "prs3")  # the whole range

    def sign(q):
        return np.sign(np.linalg.det(mech.closure_jacobian(q)[:, mech.free_dofs]))

    home = sign(mech.q_home)
    rows = sample_actuators(mech, 10, np.random.default_rng(5))
    assert all(sign(q) == home for q in mech.configurations(rows))


def test_round_trip(mech):
    acceptance.check_round_trip(mech)


@pytest.mark.slow
def test_jacobian_matches_central_differences(mech):
    acceptance.check_jacobian(mech)


def test_noise_free_recovery(mech):
    acceptance.check_recovery(mech)


@pytest.mark.slow
def test_simulate_calibrate_compensate(model, tmp_path):
    acceptance.check_cli(model, tmp_path)
