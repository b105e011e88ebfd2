"""The pieces of ``pincal acceptance`` and ``validate --cv`` callable from Python.

The commands' own tests (tests/cli/test_acceptance_*.py, test_validate_cmd.py) check the
printed figures; here: the simulated machine's errors (bounded, per unit, none without a
seed), the measured test refusing unequal repetitions, and the folds' CSV.
"""

from __future__ import annotations

import numpy as np
import pytest

from pincal.errors import MeasurementError
from pincal.io import write_measurements
from pincal.measure import Measurements
from pincal.model import load_mechanism, sample_actuators
from pincal.workflow import acceptance_machine, fold_table, measured_characteristics


def test_the_machine_has_no_errors_without_a_seed():
    nominal = load_mechanism("stewart_6ups")
    sim = acceptance_machine(nominal, None, None, 1.0, 10.0)
    assert not np.any(sim.values)
    q = sample_actuators(nominal, 3, np.random.default_rng(0))
    for row in q:
        np.testing.assert_allclose(sim.actual.forward(row).translation,
                                   nominal.forward(row).translation, atol=1e-12)  # fmt: skip


def test_the_errors_are_bounded_per_unit_and_seeded():
    nominal = load_mechanism("stewart_6ups")
    sim = acceptance_machine(nominal, "full", 3, 1.0, 10.0)  # lengths and angles
    again = acceptance_machine(nominal, "full", 3, 1.0, 10.0)
    np.testing.assert_array_equal(sim.values, again.values)
    units = np.array(sim.params.units)
    assert np.all(np.abs(sim.values[units == "m"]) <= 1e-3)
    assert np.all(np.abs(sim.values[units != "m"]) <= 10e-3)
    assert np.abs(sim.values[units != "m"]).max() > 1e-3  # the angles use their own bound
    assert acceptance_machine(nominal, None, 3, 1.0, 10.0).params.names != sim.params.names


def test_measured_poses_need_equal_repetitions(tmp_path):
    nominal = load_mechanism("stewart_6ups")
    q = sample_actuators(nominal, 2, np.random.default_rng(0))
    rows = q[[0, 0, 1]]  # pose 1 twice, pose 2 once
    poses = [nominal.forward(r) for r in rows]
    m = Measurements(rows, np.array([t.translation for t in poses]),
                     np.array([t.rotation for t in poses]), ("x", "y", "z"),
                     nominal.measured_frame, nominal.actuated)  # fmt: skip
    path = write_measurements(tmp_path / "cycles.csv", m)
    with pytest.raises(MeasurementError, match="same number"):
        measured_characteristics(str(path), nominal, nominal)


def test_fold_table_lists_each_pose_fold():
    assert fold_table(((2, 0), (1,)), 3) == "pose,fold\n0,0\n1,1\n2,0\n"
