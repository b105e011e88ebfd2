"""Monte-Carlo studies: same numbers for any n_jobs; recovers the simulated errors."""

from __future__ import annotations

import numpy as np
import pytest

import pincal
from pincal.errors import ParameterError, ShapeError
from pincal.validation import monte_carlo


def _setup():
    mech = pincal.load_mechanism("wedge3")
    params = pincal.parameters(mech, "patent")
    rows = pincal.sample_actuators(mech, 30, np.random.default_rng(0))
    truth = 1e-5 * np.random.default_rng(1).standard_normal(len(params))
    return mech, params, rows, truth


@pytest.mark.slow
def test_parallel_runs_give_the_same_numbers():
    _, _, rows, truth = _setup()
    noise = {"position": 0.005, "orientation": 0.01}
    one = monte_carlo("wedge3", "patent", rows, truth, noise, runs=4, seed=3, n_jobs=1)
    two = monte_carlo("wedge3", "patent", rows, truth, noise, runs=4, seed=3, n_jobs=2)
    np.testing.assert_array_equal(one.values, two.values)
    np.testing.assert_array_equal(one.success, two.success)
    other = monte_carlo("wedge3", "patent", rows, truth, noise, runs=4, seed=4, n_jobs=1)
    assert not np.array_equal(one.values, other.values)  # the seed matters


def test_noise_free_runs_recover_the_identifiable_truth():
    mech, params, rows, truth = _setup()
    study = monte_carlo("wedge3", "patent", rows, truth, None, runs=2, seed=0)
    assert study.values.shape == (2, len(params)) and study.success.all()
    np.testing.assert_array_equal(study.values[0], study.values[1])  # no noise: same data
    J = pincal.identification_jacobian(mech, params, rows)
    # the identifiable combinations of the errors are recovered exactly
    np.testing.assert_allclose(J @ study.values[0], J @ truth, atol=1e-10)


def test_bad_arguments_raise_specific_errors():
    _, _, rows, truth = _setup()
    with pytest.raises(ParameterError):
        monte_carlo("wedge3", "patent", rows, truth, None, runs=0)
    with pytest.raises(ShapeError):
        monte_carlo("wedge3", "patent", rows[:, :1], truth, None, runs=1)
    with pytest.raises(ParameterError):
        monte_carlo("wedge3", "patent", rows, truth[:-1], None, runs=1)


@pytest.mark.slow
def test_a_local_dask_cluster_gives_the_serial_numbers():
    pytest.importorskip("distributed")
    _, _, rows, truth = _setup()
    noise = {"position": 0.005, "orientation": 0.01}
    one = monte_carlo("wedge3", "patent", rows, truth, noise, runs=4, seed=3, n_jobs=1)
    dask = monte_carlo("wedge3", "patent", rows, truth, noise, runs=4, seed=3, scheduler="local:2")
    np.testing.assert_array_equal(one.values, dask.values)
    np.testing.assert_array_equal(one.success, dask.success)
