"""Compliance on the identified machine: forces of the estimate at the deflected pose.

The residual model of a loaded term (a Stewart platform's leg compliance under a
payload) takes the joints to the fixed point ``q = u + c·τ(q; estimate)``; its Jacobian,
the load's change with the geometry included, matches central differences of the
residuals, and the geometric part of it is not negligible (dropping it fails).
"""

from __future__ import annotations

import numpy as np
import pytest

import pincal
from pincal.identification.problem._problem import CalibrationProblem
from pincal.model import Payload, deflected_joints, with_joint_terms, with_payload
from pincal.model.params._term_compliance import actuator_load


@pytest.fixture(scope="module")
def point():
    mech = with_payload(pincal.load_mechanism("stewart_6ups"), Payload(20.0, (0.05, -0.02, 0.1)))
    params = with_joint_terms(mech, pincal.parameters(mech, "stewart42"), ("compliance",))
    rng = np.random.default_rng(3)
    rows = pincal.sample_actuators(mech, 6, rng)
    meas = pincal.simulate_measurements(mech, rows, pincal.NoiseModel(0.01, 0.01), rng)
    v = np.zeros(len(params))
    v[:42] = rng.normal(0.0, 1e-3, 42)  # 1 mm geometric errors
    v[42:] = -4e-5 * rng.uniform(0.5, 1.5, 6)  # ≈ 2 mm sag at 50 N
    return mech, params, meas, v


def test_joints_are_the_fixed_point_of_the_estimate_forces(point):
    mech, params, meas, v = point
    est = params.apply(mech, params.linearise(v))
    q = deflected_joints(est, params, v, meas.q_act)
    tau = actuator_load(est, q)
    np.testing.assert_allclose(q, meas.q_act + v[42:] * tau, rtol=0, atol=1e-12)
    # the deflection is of millimetres and the nominal forces at the command miss it
    nominal = meas.q_act + v[42:] * actuator_load(mech, meas.q_act)
    assert np.max(np.abs(q - meas.q_act)) > 1e-3
    assert np.max(np.abs(q - nominal)) > 1e-6


def _fd(problem, v, k, h):
    vp, vm = v.copy(), v.copy()
    vp[k] += h
    vm[k] -= h
    rp = problem.evaluate(vp, jacobian=False)[0]
    rm = problem.evaluate(vm, jacobian=False)[0]
    return (rp - rm) / (2 * h)


def test_jacobian_matches_finite_differences(point):
    mech, params, meas, v = point
    problem = CalibrationProblem(mech, params, meas)
    _, J, _ = problem.evaluate(v)
    steps = [1e-7] * 42 + [1e-9] * 6
    J_fd = np.column_stack([_fd(problem, v, k, h) for k, h in enumerate(steps)])
    scale = np.abs(J_fd).max(axis=0)
    assert np.max(np.abs(J - J_fd).max(axis=0) / scale) < 1e-4
    # the load's change with the geometry is part of it: without it the columns differ
    frozen = CalibrationProblem(mech, params, meas)
    frozen.poses.term_basis = lambda m, x: _no_geometry(frozen.poses, m, x)  # type: ignore[method-assign]
    _, J0, _ = frozen.evaluate(v)
    assert np.max(np.abs(J0 - J_fd)[:, :42].max(axis=0) / scale[:42]) > 1e-3


def _no_geometry(poses, mech, values):
    from pincal.model import deflection_jacobian

    q = poses.joint_values(mech, values)
    return deflection_jacobian(mech, poses.params, values, q, poses.basis, lambda _: mech)
