"""Random actuator rows of a machine without a pose workspace, screened in batches.

The 3-PRS test machine gives only slider ranges: most draws cannot be assembled. The
sampler closes blocks of draws with the batched solve; every row it returns must be
feasible by the pose-by-pose definition (forward kinematics on home's branch, away
from singularities), inside the ranges, and reproducible from the seed.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import pincal
from pincal.errors import ConvergenceError, ModelFileError

PRS3 = Path(__file__).parent / "machines" / "prs3"


@pytest.fixture(scope="module")
def mech():
    m = pincal.load_mechanism(PRS3)
    assert not m.workspace.pose and m.batch_solvable  # the case this is about
    return m


def test_rows_are_feasible_inside_the_ranges_and_reproducible(mech):
    rows = pincal.sample_actuators(mech, 40, np.random.default_rng(3))
    assert rows.shape == (40, len(mech.actuated))
    lo, hi = np.array([mech.workspace.joints[a] for a in mech.actuated]).T
    assert np.all((rows >= lo) & (rows <= hi))
    for row in rows:  # the pose-by-pose solver closes each one on home's branch
        q = mech.configuration(row)
        assert np.max(np.abs(mech.closure_residual(q))) <= 1e-12
    again = pincal.sample_actuators(mech, 40, np.random.default_rng(3))
    np.testing.assert_array_equal(rows, again)


def test_most_draws_are_infeasible_yet_sampling_succeeds(mech):
    lo, hi = np.array([mech.workspace.joints[a] for a in mech.actuated]).T
    draws = np.random.default_rng(5).uniform(lo, hi, size=(200, len(lo)))
    ok = mech.try_configurations_batch(draws)[1]
    assert ok.mean() < 0.5
    assert len(pincal.sample_actuators(mech, 30, np.random.default_rng(5))) == 30


def test_too_few_feasible_draws_is_a_clear_error(mech):
    with pytest.raises(ModelFileError, match=r"only \d+ of 500 random poses were feasible"):
        pincal.sample_actuators(mech, 500, np.random.default_rng(0), max_tries_per_pose=1)


@pytest.mark.slow  # ~20 s; screened sampling itself is checked fast above
def test_closable_batch_decides_most_draws_in_batch(monkeypatch):
    """Infeasible draws mostly cost a batched solve, not a failing pose-by-pose continuation,
    and the verdicts are the pose-by-pose solver's."""
    m = pincal.load_mechanism(PRS3)
    lo, hi = np.array([m.workspace.joints[a] for a in m.actuated]).T
    draws = np.random.default_rng(1).uniform(lo, hi, size=(150, len(lo)))
    one_by_one = m.loop_solver.configuration
    calls = []

    def counted(*args, **kwargs):
        calls.append(1)
        return one_by_one(*args, **kwargs)

    monkeypatch.setattr(m.loop_solver, "configuration", counted)
    ok = m.closable_batch(draws)
    infeasible = int((~ok).sum())
    assert infeasible > 75 and len(calls) < 0.2 * infeasible
    monkeypatch.undo()
    pose = np.zeros(len(draws), dtype=bool)
    for j, row in enumerate(draws):
        try:
            m.configuration(row)
            pose[j] = True
        except ConvergenceError:
            pass
    assert np.all(pose[ok])  # every row said closable closes pose by pose
    assert (pose & ~ok).sum() <= 2  # rarely, one only the damped pose-by-pose solve closes
