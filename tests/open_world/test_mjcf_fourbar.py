"""Machine style: an MJCF four-bar (tests/model/mjcf/fourbar.xml: one ``connect``)."""

from __future__ import annotations

from pathlib import Path

import pytest

from pincal.model import load_mechanism
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
