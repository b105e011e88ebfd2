"""Compensation with joint terms: commands that include the deflection at the target's load."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from pincal.compensation import JointTermCorrection, compensate
from pincal.identification import identify
from pincal.measure import NoiseModel, simulate_measurements
from pincal.model import (
    Payload,
    actual_joint_values,
    load_mechanism,
    sample_actuators,
    with_joint_terms,
    with_payload,
)
from pincal.sensitivity import parameters

NOISE = NoiseModel(position=0.01, orientation=0.01)  # [mm], [mrad]


@pytest.fixture(scope="module")
def compliant_arm():
    """A UR5 with a 3 kg tool, geometric errors and joint compliance; 60 measured poses."""
    mech = with_payload(load_mechanism("ur5"), Payload(3.0, (0.0, 0.0, 0.05)))
    geo = parameters(mech, "base")
    full = with_joint_terms(mech, geo, ["compliance"])
    rng = np.random.default_rng(11)
    truth = np.zeros(len(full))
    truth[: len(geo)] = rng.normal(0.0, 1e-4, len(geo))
    truth[full.joint_terms] = rng.normal(0.0, 2e-5, full.joint_terms.size)  # [rad/(N·m)]
    rows = sample_actuators(mech, 60, rng)
    actual = full.apply(mech, truth)
    meas = simulate_measurements(actual, actual_joint_values(mech, full, truth, rows), NOISE, rng)
    meas = dataclasses.replace(meas, q_act=rows.copy())
    return mech, geo, full, truth, meas, rng


def _reached_error(mech, full, truth, commands, targets) -> np.ndarray:
    """Position error [m] of the true machine driven with ``commands`` at its targets."""
    actual = full.apply(mech, truth)
    joints = actual_joint_values(mech, full, truth, commands)
    return np.array(
        [
            np.linalg.norm(actual.forward(q).translation - T.translation)
            for q, T in zip(joints, targets, strict=True)
        ]
    )


def test_commands_with_compliance_reach_targets_better(compliant_arm):
    mech, geo, full, truth, meas, rng = compliant_arm
    rows = sample_actuators(mech, 15, rng)
    targets = [mech.forward(r) for r in rows]
    only_geo = identify(mech, geo, meas, "gauss-newton")
    with_terms = identify(mech, full, meas, "gauss-newton")
    terms = JointTermCorrection.from_names(mech, with_terms.names, with_terms.full_values)
    assert len(terms.params) == 6 and all("rad/(N·m)" in line for line in terms.lines())
    plain = compensate(only_geo.calibrated, targets, check_limits=False, starts=rows)
    loaded = compensate(
        with_terms.calibrated, targets, check_limits=False, starts=rows, joint_terms=terms
    )
    assert plain.deflection is None and loaded.deflection is not None
    assert plain.reachable.all() and loaded.reachable.all()
    e_plain = _reached_error(mech, full, truth, plain.q_act, targets)
    e_terms = _reached_error(mech, full, truth, loaded.q_act, targets)
    rms = [1e6 * np.sqrt(np.mean(e**2)) for e in (e_plain, e_terms)]
    print(f"RMS miss [µm]: geometric {rms[0]:.1f}, geometric+compliance {rms[1]:.1f}")
    # geometric-only leaves the load-dependent part: 10x worse than with the terms
    assert np.sqrt(np.mean(e_terms**2)) < 0.1 * np.sqrt(np.mean(e_plain**2))
    assert np.sqrt(np.mean(e_terms**2)) < 20e-6  # [m], noise 10 µm per component
    # the commands undo the deflection the terms add at them
    cal = with_terms.calibrated
    for T, u, d in zip(targets[:3], loaded.q_act, loaded.deflection, strict=False):
        assert np.allclose(cal.forward(u + d).homogeneous, T.homogeneous, atol=1e-9)


def test_exact_terms_reach_targets_exactly(compliant_arm):
    """With the true values, compensated commands put the true machine on its targets."""
    mech, _, full, truth, _, rng = compliant_arm
    rows = sample_actuators(mech, 5, rng)
    targets = [mech.forward(r) for r in rows]
    actual = full.apply(mech, truth)
    terms = JointTermCorrection.of(mech, full, truth)
    out = compensate(actual, targets, check_limits=False, starts=rows, joint_terms=terms)
    assert np.max(_reached_error(mech, full, truth, out.q_act, targets)) < 1e-9
    assert np.max(np.abs(out.deflection)) > 1e-4  # [rad]: the load moves the joints
