"""Machine style: an MJCF Delta (tests/model/mjcf/delta.xml: ball joints, six
``connect`` closures to a free platform; delta.yaml adds the workspace)."""

from __future__ import annotations

from pathlib import Path

import pytest

from pincal.model import load_mechanism
from tests.open_world import acceptance
from tests.open_world.machines import MJCF


@pytest.fixture(scope="module")
def model() -> Path:
    return MJCF / "delta.xml"


@pytest.fixture(scope="module")
def mech(model):
    return load_mechanism(model)


def test_loads_from_mjcf(mech):
    from pincal.model import degenerate_translations

    assert mech.mobility == 3 and len(mech.closures) == 6
    # each MJCF ball joint is three revolutes meeting at one point
    assert len(degenerate_translations(mech)) == 6 * 2 * 3


def test_round_trip(mech):
    acceptance.check_round_trip(mech)


@pytest.mark.slow
def test_jacobian_matches_central_differences(mech):
    acceptance.check_jacobian(mech)


def test_noise_free_recovery(mech):
    acceptance.check_recovery(mech)


def test_simulate_calibrate_compensate(model, tmp_path):
    acceptance.check_cli(model, tmp_path)
