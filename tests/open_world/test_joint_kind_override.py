"""Machine style: ``joint_name``/``joint_type`` in the sidecar turn a revolute placeholder
into a ball joint (tests/model/machines/rssr: spatial RSSR, measured position)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pincal.model import load_mechanism
from tests.open_world import acceptance
from tests.open_world.machines import RSSR_CRANK_RANGE, copy_machine


@pytest.fixture(scope="module")
def model(tmp_path_factory) -> Path:
    # the crank's URDF range is ±3.14 and the rocker tip is at the same place for crank
    # angles a and −a (mirror symmetry; crank 0 is a dead point of the output): the copy
    # under test gets a home and a workspace on one side of the dead point
    workspace = {"joints": {"crank_mot": list(RSSR_CRANK_RANGE)}}
    return copy_machine(
        tmp_path_factory.mktemp("m"), "rssr", home={"crank_mot": 0.5}, workspace=workspace
    )


@pytest.fixture(scope="module")
def mech(model):
    return load_mechanism(model)


def test_loads_with_a_ball_joint(mech):
    j = mech.model.getJointId("ball_a")
    assert mech.model.joints[j].shortname() == "JointModelSpherical"
    assert mech.mobility == 1 and np.isfinite(mech.actuator_limits).all()


def test_round_trip(mech):
    acceptance.check_round_trip(mech)


def test_jacobian_matches_central_differences(mech):
    acceptance.check_jacobian(mech)


def test_noise_free_recovery_of_the_measured_quantity(mech):
    acceptance.check_recovery(mech, tol=None)


def test_noise_free_recovery(mech):
    acceptance.check_recovery(mech)


def test_simulate_calibrate_compensate(model, tmp_path):
    acceptance.check_cli(model, tmp_path)
