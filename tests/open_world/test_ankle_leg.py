"""Machine style: a legged robot's 2-RSU parallel ankle (machines.ankle_2rsu): two
loops, ball and U joints emulated by revolutes meeting at a point, and — in the
variant with ``zero_limits`` — every joint written with ``<limit lower="0" upper="0">``
and no sidecar workspace (issue 28, causes 1, 2 and 4)."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pytest

from pincal.errors import ConvergenceError
from pincal.identification import GaussNewtonOptions, identify
from pincal.measure import simulate_measurements
from pincal.model import Mechanism, degenerate_translations, load_mechanism, sample_actuators
from pincal.model.reach._range_explore import BACK_OFF, DEFAULT_SPAN, STEPS, explored_ranges
from pincal.sensitivity import identifiability, parameters
from tests.open_world import acceptance
from tests.open_world.machines import ANKLE_MOTOR_RANGE, ankle_2rsu, write_machine


@pytest.fixture(scope="module")
def model(tmp_path_factory) -> Path:
    return write_machine(tmp_path_factory.mktemp("m"), "ankle", *ankle_2rsu())


@pytest.fixture(scope="module")
def mech(model):
    return load_mechanism(model)


def test_two_loops_and_emulated_joints(mech):
    assert len(mech.closures) == 2 and mech.mobility == 2
    split = set(degenerate_translations(mech))
    expected = {
        f"{j}.t{d}" for j in ("ball_b_l", "ball_c_l", "ball_b_r", "ball_c_r") for d in "xyz"
    }
    assert expected | {f"ankle_roll.t{d}" for d in "xyz"} == split


def test_round_trip(mech):
    acceptance.check_round_trip(mech)


def test_jacobian_matches_central_differences(mech):
    acceptance.check_jacobian(mech)


def test_noise_free_recovery(mech):
    """Cause 2: a legged mechanism with several loops recovers to 1e-9."""
    acceptance.check_recovery(mech)


def test_simulate_calibrate_compensate(model, tmp_path):
    acceptance.check_cli(model, tmp_path)


# ------------------------------------------------------------------ cause 4: `full`
def test_translations_inside_emulated_joints_are_held(mech):
    """Asked to fit them (here: the ``full`` set, fitting the base preset and every
    translation between coincident axes), identify() never moves a translation that
    would split an emulated joint (the mechanism may not even be buildable): they are
    reported apart, and the rest recovers the simulated errors to 1e-9."""
    full, base = parameters(mech, "full"), parameters(mech, "base")
    split = degenerate_translations(mech)
    rows = sample_actuators(mech, 30, np.random.default_rng(11))
    truth = np.random.default_rng(1).normal(0, 2e-4, len(base))
    meas = simulate_measurements(base.apply(mech, truth), rows)
    res = identify(mech, full, meas, fit=[*base.names, *split])
    assert res.success, res.message
    assert set(res.identifiability.splits_joint_names) == set(split)
    assert not any(res.identified[full.index(n)] for n in split)
    assert np.all(res.full_values[[full.index(n) for n in split]] == 0.0)
    assert f"{len(split)} would split an emulated ball or universal joint" in res.message
    assert any("would split an emulated" in line for line in res.identifiability.describe())
    got = res.full_values[[full.index(n) for n in base.names]]
    assert np.max(np.abs(got - truth)) <= 1e-9


# ------------------------------------------------------------------ cause 1: 0/0 limits
@pytest.fixture(scope="module")
def zero():
    return Mechanism(*ankle_2rsu(zero_limits=True))


def test_zero_width_limits_are_explored_from_home(zero, caplog):
    with caplog.at_level(logging.WARNING, logger="pincal.model.reach._range_explore"):
        rows = sample_actuators(zero, 20, np.random.default_rng(0))
    said = [r.getMessage() for r in caplog.records]
    assert any(
        "'mot_l'" in m and "found by continuation from home" in m and "not declared" in m
        for m in said
    )
    lo, hi = explored_ranges(zero)[0]  # kept from sample_actuators (memo)
    span = DEFAULT_SPAN["rad"]
    assert lo == pytest.approx(-span)  # that side closes over the whole default span
    assert 0.5 < hi < span  # that side stops where the loops stop closing
    assert np.all(rows[:, 0] >= lo) and np.all(rows[:, 0] <= hi)
    # the explored end closes; BACK_OFF + 1 steps further does not (on home's branch)
    q0 = zero.actuators_of(zero.q_home)
    q_prev = zero.q_home
    for v in np.linspace(0.0, hi, 40)[1:]:
        q_prev = zero.configuration(np.r_[v, q0[1]], q_guess=q_prev)
    for i in range(1, BACK_OFF + 1):
        q_prev = zero.configuration(np.r_[hi + i * span / STEPS, q0[1]], q_guess=q_prev)
    with pytest.raises(ConvergenceError):
        zero.configuration(np.r_[hi + (BACK_OFF + 1) * span / STEPS, q0[1]], q_guess=q_prev)


def test_zero_width_limits_identifiability_with_default_poses(zero):
    """The default poses of identifiability() are feasible: a full analysis."""
    base = parameters(zero, "base")
    ident = identifiability(zero, base)
    assert ident.full_rank and ident.rank == len(base) > 20


def test_declared_ranges_are_used_as_given(mech):
    rows = sample_actuators(mech, 20, np.random.default_rng(0))
    assert np.all(rows >= ANKLE_MOTOR_RANGE[0]) and np.all(rows <= ANKLE_MOTOR_RANGE[1])
    assert explored_ranges(mech) == {}  # nothing explored


def test_zero_width_limits_batched_and_pose_by_pose_agree(zero):
    """At wide poses (|motor| > 1 rad) rows the batched Newton leaves are closed from
    home, as configuration() does: started from the previous row's solution, a direct
    solve closed two of them with the foot turned over (another assembly mode, same
    branch sign, 9 cm away)."""
    rows = sample_actuators(zero, 30, np.random.default_rng(11))
    Q, _ = zero.configurations_batch(rows)
    for row, q in zip(rows, Q, strict=True):
        a = zero.frame_placement(q).translation
        b = zero.frame_placement(zero.configuration(row)).translation
        assert np.max(np.abs(a - b)) <= 1e-9


@pytest.mark.slow  # ~18 s; the 0/0 ankle's identifiability and closing stay fast above
def test_zero_width_limits_noise_free_recovery(zero):
    """With every row closed on home's assembly mode, the 0/0-limits ankle recovers a
    random error on its base set to 1e-9 over the explored range (cause 2)."""
    acceptance.check_recovery(zero)


def test_estimation_stops_when_the_fits_do_not_converge(zero):
    """Where the fit cannot converge (here: cut to 2 iterations, without the
    Levenberg–Marquardt fallback, whose evaluation limit grows with the parameter count),
    the noise estimate stops after two fits instead of re-fitting 30 times."""
    base = parameters(zero, "base")
    rows = sample_actuators(zero, 30, np.random.default_rng(11))
    truth = np.random.default_rng(1).normal(0, 2e-4, len(base))
    meas = simulate_measurements(base.apply(zero, truth), rows)
    res = identify(zero, base, meas, options=GaussNewtonOptions(max_iterations=2, fallback=False))
    assert not res.success and res.weighting.rounds == 2 and not res.weighting.converged
