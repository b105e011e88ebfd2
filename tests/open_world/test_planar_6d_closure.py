"""Machine style: a ``6d`` closure of a planar loop (rank-deficient: 6 rows of rank 3):
the five-bar of tests/sensitivity/five_bar.py, measured x, y, rz.

``pincal.identify`` must not fit parameters that break loop closure; they are left out
of the fitted set and counted in its message.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import pincal
from pincal.model import Mechanism, load_mechanism, sample_actuators
from pincal.sensitivity import closure_breaking, parameters
from tests.open_world import acceptance
from tests.open_world.machines import write_machine
from tests.sensitivity.five_bar import FIVE_BAR_SIDECAR, FIVE_BAR_URDF


@pytest.fixture(scope="module")
def model(tmp_path_factory) -> Path:
    return write_machine(tmp_path_factory.mktemp("m"), "five_bar", FIVE_BAR_URDF, FIVE_BAR_SIDECAR)


@pytest.fixture(scope="module")
def mech(model):
    return load_mechanism(model)


def test_loads_with_a_rank_deficient_closure(mech):
    Jc = mech.closure_jacobian(mech.q_home)[:, mech.free_dofs]
    assert Jc.shape[0] == 6 and np.linalg.matrix_rank(Jc) == 3 and mech.mobility == 2


def test_round_trip(mech):
    acceptance.check_round_trip(mech)


def test_jacobian_matches_central_differences(mech):
    acceptance.check_jacobian(mech)


def test_noise_free_recovery(mech):
    acceptance.check_recovery(mech)


def test_simulate_calibrate_compensate(model, tmp_path):
    acceptance.check_cli(model, tmp_path)


def test_base_preset_has_no_closure_breaking_parameter(mech):
    base = parameters(mech, "base")
    rows = sample_actuators(mech, 24, np.random.default_rng(3))
    assert not closure_breaking(mech, base, rows).any()


@pytest.mark.parametrize("measured", ["x y rz", "pose"])
def test_identify_does_not_fit_parameters_that_break_closure(measured):
    """With the whole pose measured, out-of-plane parameters have least-squares columns
    and used to be fitted (5 of them); now they are held and counted."""
    mech = Mechanism(FIVE_BAR_URDF, dict(FIVE_BAR_SIDECAR, measured=measured), name="five_bar")
    full = parameters(mech, "full")
    rows = sample_actuators(mech, 24, np.random.default_rng(3))
    breaking = closure_breaking(mech, full, rows)
    assert breaking.sum() == 18
    truth = np.zeros(len(full))
    base = pincal.identifiability(mech, full, rows).base
    truth[base] = np.random.default_rng(4).normal(0, 3e-4, base.size)
    meas = pincal.simulate_measurements(full.apply(mech, truth), rows)
    res = pincal.identify(mech, full, meas)
    assert res.success, res.message
    assert not (res.identified & breaking).any()
    assert "(18 break loop closure)" in res.message
    assert set(res.identifiability.breaks_closure) == set(np.flatnonzero(breaking))
    assert res.after.max_position <= 1e-9


def test_identify_without_reduction_names_the_breaking_parameters(mech):
    full = parameters(mech, "full")
    rows = sample_actuators(mech, 24, np.random.default_rng(3))
    meas = pincal.simulate_measurements(mech, rows)
    grouped = r"18 parameters break loop closure at \d+ joints .*act_a\.\{[^}]*rx"  # one line
    with pytest.raises(pincal.UnidentifiableError, match=grouped):
        pincal.identify(mech, full, meas, reduce=False)
