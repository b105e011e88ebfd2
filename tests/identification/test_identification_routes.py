"""One IdentificationProblem over one or several data sets: the batched and the joint fit.

A pose file alone is fitted by the batched residual model; several data sets (pose,
instrument, socket files in any mix) by the joint model. Both end in one finishing step,
so where they overlap — one pose file — they give the same values and covariance.
"""

from __future__ import annotations

import numpy as np
import pytest

from pincal.errors import MeasurementError, ParameterError, SolverOptionError
from pincal.identification import IdentificationProblem, identify, identify_instruments
from pincal.measure import Distance, Point, simulate_instrument, simulate_measurements
from pincal.model import sample_actuators
from pincal.validation import pose_errors

NOISE = {"position": 0.01, "orientation": 0.1}  # mm, mrad


@pytest.fixture(scope="module")
def truth(stewart42) -> np.ndarray:
    return np.random.default_rng(8).uniform(-5e-4, 5e-4, len(stewart42))


@pytest.fixture(scope="module")
def rows(stewart) -> np.ndarray:
    return sample_actuators(stewart, 90, np.random.default_rng(21))


def test_a_pose_file_gives_the_same_fit_through_the_batched_and_the_joint_model(
    stewart, stewart42, truth, rows
):
    actual = stewart42.apply(stewart, truth)
    meas = simulate_measurements(actual, rows[:40], NOISE, np.random.default_rng(3))
    batched = identify(IdentificationProblem(stewart, stewart42, meas))
    joint = identify_instruments(stewart, stewart42, [meas], weak_bound=None).result
    assert batched.success and joint.success, (batched.message, joint.message)
    assert np.array_equal(batched.identified, joint.identified)
    assert np.abs(batched.full_values - joint.full_values).max() < 1e-9  # [m, rad]
    scale = np.abs(batched.covariance).max()
    assert np.abs(batched.covariance - joint.covariance).max() < 1e-9 * scale
    assert joint.reduced_chi2 == pytest.approx(batched.reduced_chi2, rel=1e-9)
    assert joint.after.rms_position == pytest.approx(batched.after.rms_position, rel=1e-6)
    # and the fit recovers the simulated errors within its own σ
    z = (batched.values - truth[batched.identified]) / batched.std
    assert np.abs(z).max() < 5.0


def test_a_pose_file_alone_in_a_list_is_the_batched_fit(stewart, stewart42, truth, rows):
    meas = simulate_measurements(
        stewart42.apply(stewart, truth), rows[:40], NOISE, np.random.default_rng(4)
    )
    listed = IdentificationProblem(stewart, stewart42, [meas])
    assert not listed.joint and listed.pose_file is meas
    a, b = identify(listed), identify(IdentificationProblem(stewart, stewart42, meas))
    assert np.array_equal(a.full_values, b.full_values) and a.message == b.message


def test_a_mixed_list_is_identified_through_identify(stewart, stewart42, truth, rows):
    actual = stewart42.apply(stewart, truth)
    rng = np.random.default_rng(9)
    P = np.array([stewart.frame_placement(q).translation for q in stewart.configurations(rows)])
    pivot = np.r_[P[:80].mean(axis=0) + np.array([0.01, 0.02, -0.15]), 1e-3]
    pos = simulate_measurements(actual, rows[:12], {"position": 0.005, "orientation": 1}, rng,
                                ("x", "y", "z"))  # fmt: skip
    bar = simulate_instrument(actual, Distance(1e-6), pivot,
                              rows[12:52], rng)  # fmt: skip
    gauge = simulate_instrument(actual, Point(1e-6, direction=(0.1, 0, 1)), np.array([0.03]),
                                rows[52:80], rng)  # fmt: skip
    labels = ["tracker", "bar", "gauge"]
    problem = IdentificationProblem(stewart, stewart42, [pos, bar, gauge], labels=labels)
    assert problem.joint and len(problem.datasets) == 3
    res = identify(problem)
    assert res.success, res.message
    assert 0.3 < res.reduced_chi2 < 2.0  # each file whitened by its own σ
    assert res.joint is not None and res.joint.datasets == tuple(labels)
    assert "bar.pivot_x" in res.joint.instruments
    # the same fit as the convenience that also returns the instrument details
    same = identify_instruments(stewart, stewart42, [pos, bar, gauge], labels=labels).result
    assert np.abs(res.full_values - same.full_values).max() < 1e-12
    # the calibrated machine predicts held-out tool points far better than the nominal one
    held = rows[80:]
    after = pose_errors(res.calibrated, actual, held).position.max()
    before = pose_errors(stewart, actual, held).position.max()
    assert after < 0.1 * before, (after, before)


def test_a_joint_problem_refuses_what_only_a_pose_file_takes(stewart, stewart42, rows):
    meas = simulate_measurements(stewart, rows[:12], NOISE, np.random.default_rng(1))
    bar = simulate_instrument(stewart, Distance(1e-6), np.r_[0.0, 0.0, 0.5, 0.0], rows[12:40],
                              np.random.default_rng(2))  # fmt: skip
    for extra, word in (({"fit": stewart42.names[:3]}, "fit"), ({"noise": NOISE}, "noise"),
                        ({"initial": np.zeros(len(stewart42))}, "initial"),
                        ({"reduce": False}, "reduce=False")):  # fmt: skip
        with pytest.raises(ParameterError, match=word):
            IdentificationProblem(stewart, stewart42, [meas, bar], **extra)
    silent = simulate_measurements(stewart, rows[:12])  # exact: no noise declared
    with pytest.raises(MeasurementError, match="pose data set 'pose0' declares no noise"):
        IdentificationProblem(stewart, stewart42, [silent, bar])
    with pytest.raises(MeasurementError, match="at least one"):
        IdentificationProblem(stewart, stewart42, [])
    with pytest.raises(MeasurementError, match="ndarray"):
        IdentificationProblem(stewart, stewart42, [meas, np.zeros(3)])
    with pytest.raises(MeasurementError, match="a list of data sets"):
        identify(stewart, stewart42, "lm")
    problem = IdentificationProblem(stewart, stewart42, [meas, bar])
    with pytest.raises(MeasurementError, match="joint_model"):
        _ = problem.model
    with pytest.raises(SolverOptionError, match="'gauss-newton' or 'lm'"):
        identify(problem, method="qpso")
