"""Machine style: an MJCF four-bar (tests/model/mjcf/fourbar.xml: one ``connect``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from pincal.model import load_mechanism, sample_actuators
from tests.open_world import acceptance
from tests.open_world.machines import MJCF


@pytest.fixture(scope="module")
def model() -> Path:
    return MJCF / "fourbar.xml"


@pytest.fixture(scope="module")
def mech(model):
    return load_mechanism(model)


def test_loads_from_mjcf(mech):
    assert mech.n_actuated == 1 and len(mech.closures) == 1


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


def test_forward_kinematics_stays_on_home_branch_from_any_guess(mech):
    """The 3d closure of the planar loop has a redundant row (3 rows, rank 2): the branch
    is checked on the square block of independent rows (measured: 3 of 8 random guesses
    close the loop on the other branch, which was returned before)."""
    assert mech.home_branch == 0.0 and mech.idle_branch != 0.0
    row = sample_actuators(mech, 1, np.random.default_rng(0))[0]
    expected = mech.forward(row)
    for k in range(8):
        step = np.random.default_rng(k).normal(0.0, 2.0, mech.model.nv)
        guess = pin.integrate(mech.model, mech.configuration(row), step)
        got = mech.frame_placement(mech.configuration(row, q_guess=guess))
        assert np.allclose(got.homogeneous, expected.homogeneous, atol=1e-9)
