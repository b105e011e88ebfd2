"""Failures users met on their own machines, with the message they now see."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

import pincal
from pincal.cli import main
from pincal.errors import TooFewPosesError
from pincal.model import load_mechanism, sample_actuators
from pincal.sensitivity import parameters
from tests.open_world.machines import MJCF, write_machine
from tests.sensitivity.five_bar import FIVE_BAR_SIDECAR, FIVE_BAR_URDF


@pytest.fixture(scope="module")
def delta():
    return load_mechanism(MJCF / "delta.xml")


def test_equations_are_counted_against_the_base_set_not_the_preset(delta):
    """30 poses × 3 = 90 equations for the 204 parameters of `full`: enough, because
    only the identifiable base set is fitted (it used to be refused)."""
    full = parameters(delta, "full")
    rows = sample_actuators(delta, 30, np.random.default_rng(0))
    ident = pincal.identifiability(delta, full, rows)
    assert ident.rank < 90 < len(full)
    truth = np.zeros(len(full))
    base = parameters(delta, "base")
    truth[[full.index(n) for n in base.names]] = np.random.default_rng(1).normal(0, 2e-4, len(base))
    meas = pincal.simulate_measurements(full.apply(delta, truth), rows)
    res = pincal.identify(delta, full, meas)
    assert res.success, res.message
    assert res.message.startswith(f"identified the {ident.rank} base parameters; held")
    assert res.after.max_position <= 1e-9


def test_too_few_poses_names_the_counts(delta):
    full = parameters(delta, "full")
    rows = sample_actuators(delta, 5, np.random.default_rng(0))
    meas = pincal.simulate_measurements(delta, rows)
    with pytest.raises(TooFewPosesError, match=r"5 poses × 3 components = 15 equations for 204"):
        pincal.identify(delta, full, meas)


def test_info_counts_parameters_that_break_loop_closure(tmp_path):
    model = write_machine(tmp_path, "five_bar", FIVE_BAR_URDF, FIVE_BAR_SIDECAR)
    res = CliRunner().invoke(main, ["info", str(model)])
    assert res.exit_code == 0, res.output
    assert "preset 'full': 42 parameters, 13 identifiable, 18 break loop closure" in res.output
    assert "preset 'base': 13 parameters, all identifiable" in res.output
    res = CliRunner().invoke(main, ["info", str(model), "--preset", "full"])
    closing = [t for t in res.output.splitlines() if "parameters break loop closure at" in t]
    assert len(closing) == 1, closing  # one grouped line, not one per parameter
    assert "18 parameters break loop closure at " in closing[0] and "act_a.{" in closing[0]
