"""Machine style: a ball joint emulated by three revolutes with intersecting axes
(machines.rssr_emulated_ball). The translations between the coincident axes are
degenerate; the ``base`` preset leaves them out."""

from __future__ import annotations

from pathlib import Path

import pytest

from pincal.model import load_mechanism
from tests.open_world import acceptance
from tests.open_world.machines import rssr_emulated_ball, write_machine


@pytest.fixture(scope="module")
def model(tmp_path_factory) -> Path:
    return write_machine(tmp_path_factory.mktemp("m"), "rssr3r", *rssr_emulated_ball())


@pytest.fixture(scope="module")
def mech(model):
    return load_mechanism(model)


def test_base_preset_leaves_out_translations_between_coincident_axes(mech):
    from pincal.model import degenerate_translations, parameters

    degenerate = {f"ball_{a}.t{d}" for a in "yz" for d in "xyz"}
    assert set(degenerate_translations(mech)) == degenerate
    assert degenerate.isdisjoint(parameters(mech, "base").names)
    assert degenerate <= set(parameters(mech, "full").names)


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
