"""The thermal term: lengths scaling by 1 + α (T − 20 °C) with a per-pose temperature.

Its Jacobian against finite differences (a serial arm's link lengths move the measured
frame; a closed loop's prismatic legs change their joint values), its definition, the
refusals (no temperature, a constant one, a link length inside a loop), and recovery of
known coefficients from simulated data.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from scipy.stats import chi2

from pincal.errors import ConditionError, ParameterError
from pincal.identification import CalibrationProblem, identify
from pincal.measure import simulate_measurements
from pincal.model import (
    actual_joint_values,
    actual_shift,
    joint_term_basis,
    joint_term_shift,
    load_mechanism,
    sample_actuators,
    with_joint_terms,
)
from pincal.sensitivity import identifiability, parameters

MACHINES = Path(__file__).parents[1] / "model" / "machines"
NOISE = {"position": 0.01, "orientation": 0.01}  # [mm], [mrad]


@pytest.fixture(scope="module")
def ur5():
    return load_mechanism("ur5")


def _measured(mech, params, truth, n, rng, span=(18.0, 28.0)):
    """Simulated measurements of ``mech`` with ``params`` at ``truth``, temperatures in span."""
    rows = sample_actuators(mech, n, rng)
    cond = {"temperature": rng.uniform(*span, n)}
    actual = params.apply(mech, truth)
    meas = simulate_measurements(
        actual, actual_joint_values(mech, params, truth, rows, cond), NOISE, rng
    )
    shift = actual_shift(mech, params, truth, rows, cond)
    return dataclasses.replace(
        meas, q_act=rows, positions=meas.positions + shift, temperature=cond["temperature"]
    )


def _fd_check(mech, params, meas, rng, columns=None) -> float:
    """Largest |J − J_fd| relative to the column's size, over ``columns`` (default all)."""
    prob = CalibrationProblem(mech, params, meas, noise=NOISE)
    scale = np.where(np.isin(np.arange(len(params)), params.joint_terms), 2e-5, 1e-4)
    x = rng.normal(0.0, 1.0, len(params)) * scale
    _, J, _ = prob.evaluate(x)
    worst = 0.0
    for k in range(len(params)) if columns is None else columns:
        e = np.zeros(len(params))
        e[k] = 1e-3 * scale[k]
        hi, _, _ = prob.evaluate(x + e, jacobian=False)
        lo, _, _ = prob.evaluate(x - e, jacobian=False)
        fd = (hi - lo) / (2 * e[k])
        size = max(float(np.abs(fd).max()), 1e-300)
        worst = max(worst, float(np.abs(J[:, k] - fd).max()) / size)
    return worst


def test_arm_link_lengths_jacobian_matches_finite_differences(ur5):
    params = with_joint_terms(ur5, parameters(ur5, "base"), ["temperature"])
    assert [params.units[k] for k in params.joint_terms] == ["1/K"] * 6
    rng = np.random.default_rng(4)
    meas = _measured(ur5, params, np.zeros(len(params)), 12, rng)
    assert _fd_check(ur5, params, meas, rng) < 1e-6


def test_mixed_chain_jacobian_matches_finite_differences():
    """TIAGo: a prismatic torso (its stroke) under a revolute arm (its links)."""
    mech = load_mechanism("tiago", "arm_tool_link")
    params = with_joint_terms(mech, parameters(mech, "base"), ["temperature"])
    assert params.names[params.joint_terms[0]] == "torso_lift_joint.thermal"
    rng = np.random.default_rng(1)
    meas = _measured(mech, params, np.zeros(len(params)), 8, rng)
    assert _fd_check(mech, params, meas, rng, params.joint_terms) < 1e-6


def test_closed_loop_legs_jacobian_matches_finite_differences():
    """A planar 3-RPR (prismatic legs in a loop, measures x y rz): joint-space terms."""
    mech = load_mechanism(MACHINES / "rpr3")
    params = with_joint_terms(mech, parameters(mech, "base"), ["temperature"])
    assert len(params.joint_terms) == 3
    rng = np.random.default_rng(5)
    meas = _measured(mech, params, np.zeros(len(params)), 10, rng)
    assert joint_term_shift(mech, params, meas.q_act, meas.conditions) is None
    assert _fd_check(mech, params, meas, rng, params.joint_terms) < 1e-6


def test_basis_and_shift_match_their_definition(ur5):
    params = with_joint_terms(ur5, parameters(ur5, ["elbow_joint.offset"]), ["temperature"])
    rng = np.random.default_rng(6)
    rows = sample_actuators(ur5, 4, rng)
    T = np.array([20.0, 25.0, 15.0, 30.0])
    cond = {"temperature": T}
    assert not np.any(joint_term_basis(ur5, params, rows, cond))  # revolute: no δq
    S = joint_term_shift(ur5, params, rows, cond)
    k = params.index("elbow_joint.thermal")
    alpha = 2e-5
    for i, row in enumerate(rows):  # exact: the upper arm 1 + α ΔT longer, the rest rigid
        longer = ur5.tree.joints["elbow_joint"].origin.translation * (1 + alpha * (T[i] - 20))
        origin = ur5.tree.joints["elbow_joint"].origin
        moved = ur5.with_joint_origins({"elbow_joint": pin.SE3(origin.rotation, longer)})
        q = ur5.with_actuators(ur5.q_home, row)
        dp = moved.frame_placement(q).translation - ur5.frame_placement(q).translation
        assert np.allclose(S[i, :, k] * alpha, dp, rtol=1e-9, atol=1e-15)
    assert np.allclose(S[0], 0.0)  # at the reference temperature nothing moves


def test_prismatic_stroke_basis():
    mech = load_mechanism(MACHINES / "rpr3")
    params = with_joint_terms(mech, parameters(mech, ["leg1.offset"]), ["temperature"])
    rows = sample_actuators(mech, 3, np.random.default_rng(1))
    T = np.array([18.0, 22.0, 27.0])
    B = joint_term_basis(mech, params, rows, {"temperature": T})
    a = mech.actuated.index("leg1")
    assert np.allclose(B[:, a, params.index("leg1.thermal")], (T - 20.0) * rows[:, a])


def test_refusals(ur5):
    params = with_joint_terms(ur5, parameters(ur5, "base"), ["temperature"])
    rng = np.random.default_rng(2)
    meas = _measured(ur5, params, np.zeros(len(params)), 10, rng)
    with pytest.raises(ConditionError, match="temperature_C"):
        CalibrationProblem(ur5, params, dataclasses.replace(meas, temperature=None), NOISE)
    with pytest.raises(ConditionError, match="varies across poses"):
        CalibrationProblem(ur5, params, dataclasses.replace(meas, temperature=np.full(10, 23.0)),
                           NOISE)  # fmt: skip
    with pytest.raises(ConditionError, match="degrees|°C"):
        joint_term_basis(ur5, params, meas.q_act, {"temperature": meas.temperature + 273.15})
    fivebar = load_mechanism(MACHINES / "fivebar")
    with pytest.raises(ParameterError, match="prismatic actuators"):
        with_joint_terms(fivebar, parameters(fivebar, "full"), ["temperature"])


def test_constant_temperature_makes_the_lengths_absorb_the_coefficients(ur5):
    """What the refusal protects: with one temperature the thermal columns are in the span
    of the link translations (the rank analysis on such data says so)."""
    params = with_joint_terms(ur5, parameters(ur5, "base"), ["temperature"])
    rows = sample_actuators(ur5, 40, np.random.default_rng(3))
    varying = identifiability(ur5, params, rows,
                              conditions={"temperature": np.linspace(18, 28, 40)})  # fmt: skip
    constant = identifiability(ur5, params, rows, conditions={"temperature": np.full(40, 25.0)})
    thermal = {params.names[k] for k in params.joint_terms}
    assert len(thermal & set(varying.base_names)) == 5  # wrist_2 ∥ shoulder_lift
    assert len(thermal & set(constant.base_names)) < 3


def test_coefficients_recovered_on_an_arm(ur5):
    """60 poses at 18–28 °C: the identified coefficients lie within their covariance."""
    params = with_joint_terms(ur5, parameters(ur5, "base"), ["temperature"])
    rng = np.random.default_rng(11)
    truth = np.zeros(len(params))
    truth[: len(params) - 6] = rng.normal(0.0, 1e-4, len(params) - 6)
    truth[params.joint_terms] = 12e-6 + rng.normal(0.0, 5e-6, 6)
    truth[params.index("wrist_2_joint.thermal")] = 0.0  # absorbed by shoulder_lift's
    meas = _measured(ur5, params, truth, 60, rng)
    res = identify(ur5, params, meas, "gauss-newton", noise=NOISE)
    ids = np.flatnonzero(res.identified)
    jt = np.isin(ids, params.joint_terms)
    assert int(jt.sum()) == 5
    e = res.values[jt] - truth[ids[jt]]
    maha = float(e @ np.linalg.solve(res.covariance[np.ix_(jt, jt)], e))
    assert maha < chi2.ppf(0.999, 5), (maha, e)
    assert np.all(np.sqrt(np.diag(res.covariance[np.ix_(jt, jt)])) < 2e-5)

