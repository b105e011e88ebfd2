"""The batched continuation: rows a direct solve from home misses, closed in batch.

The RSSR four-bar's crank turns through its whole range: from home, a direct Newton
solve closes fewer than half of the random rows, and the five-bar's direct solve lands
on the other assembly branch for about one row in ten. The batched continuation
(straight actuator path from home, adaptive steps) must close them on home's branch,
to the measured pose the pose-by-pose solver gives, independently of the other rows.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import pincal
from pincal.model.batch._batch_fk import _MIN_CONTINUATION_ROWS

MACHINES = Path(__file__).parents[1] / "model" / "machines"


@pytest.fixture(scope="module", params=["rssr", "fivebar"])
def mech(request, tmp_path_factory):
    if request.param == "fivebar":  # drawn over ±π, as before ranges were explored
        from tests.open_world.machines import copy_machine

        circle = {"joints": {m: [-np.pi, np.pi] for m in ("mot_l", "mot_r")}}
        return pincal.load_mechanism(
            copy_machine(tmp_path_factory.mktemp("m"), "fivebar", workspace=circle)
        )
    return pincal.load_mechanism(MACHINES / request.param)


@pytest.fixture(scope="module")
def rows(mech):
    return pincal.sample_actuators(mech, 240, np.random.default_rng(0))


def _direct_only(mech, rows):
    """Rows a direct batched solve from home alone accepts (no continuation): Newton from
    the first-order prediction, kept near it (a continuation step over the whole path)."""
    Q, moved = mech.batch_solver._predicted_starts(rows)  # the direct layer alone
    R = np.empty((len(rows), mech.model.njoints, 3, 3))
    p = np.empty((len(rows), mech.model.njoints, 3))
    J = np.empty((len(rows), 6, mech.model.nv))
    Jf = np.empty((len(rows), mech.n_closure_rows, mech.free_dofs.size))
    travel = np.zeros(len(rows))
    done = mech.batch_solver.close_chunks(Q, R, p, J, Jf, travel)
    done &= travel <= 0.25 * moved + 1e-7
    return mech.batch_solver.accept(Jf, done)[1]


def test_continuation_closes_what_the_direct_solve_misses(mech, rows):
    direct = _direct_only(mech, rows)
    assert direct.mean() < 0.95  # the case this is about
    Q, ok, bk = mech.try_configurations_batch(rows)
    # all but a short tail (left to the pose-by-pose solver, faster for a few rows)
    assert np.all(ok[direct]) and (~ok).sum() < _MIN_CONTINUATION_ROWS < (~direct).sum()
    assert np.all(bk.closure_factor.sign()[ok] == mech.idle_branch)
    for i in np.nonzero(ok & ~direct)[0]:
        assert np.max(np.abs(mech.closure_residual(Q[i]))) <= 1e-12
        got, want = mech.frame_placement(Q[i]), mech.forward(rows[i])
        np.testing.assert_allclose(got.translation, want.translation, atol=1e-10)
        np.testing.assert_allclose(got.rotation, want.rotation, atol=1e-10)


def test_rows_do_not_depend_on_the_batch(mech, rows):
    Q_all = mech.configurations_batch(rows)[0]
    part = np.arange(0, len(rows), 3)
    Q_part = mech.configurations_batch(rows[part])[0]
    for i, j in enumerate(part):
        got, want = mech.frame_placement(Q_part[i]), mech.frame_placement(Q_all[j])
        np.testing.assert_allclose(got.translation, want.translation, atol=1e-12)
        np.testing.assert_allclose(got.rotation, want.rotation, atol=1e-12)


def test_home_predictions_are_each_rows_own(mech, rows):
    """From home, one solve serves every row: the same starts as each row's prediction
    from home's kinematics."""
    from pincal.model.batch._batch import BatchKinematics

    solver = mech.batch_solver
    home = np.tile(mech.q_home, (len(rows), 1))
    got, moved = solver._predicted_starts(rows)
    kin = mech.batch_model.kinematics(home)
    want, want_moved = solver._predict_batch(
        BatchKinematics(home, kin.rotations, kin.translations, kin.jacobian), rows
    )
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)
    np.testing.assert_allclose(moved, want_moved, rtol=1e-12)
