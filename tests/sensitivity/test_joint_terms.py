"""Joint-space error terms: parameters, basis, Jacobian columns vs finite differences."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import pincal
from pincal.errors import ParameterError
from pincal.identification import CalibrationProblem
from pincal.measure import simulate_measurements
from pincal.model import (
    joint_term_basis,
    joint_term_prior,
    load_mechanism,
    sample_actuators,
    split_model,
    with_joint_terms,
)
from pincal.sensitivity import parameters

MACHINES = Path(__file__).parents[1] / "model" / "machines"
ALL = ("compliance", "gain", "harmonics")


@pytest.fixture(scope="module")
def ur5() -> pincal.Mechanism:
    return load_mechanism("ur5")


def _fd_errors(mech, params, n_poses: int, seed: int) -> np.ndarray:
    """Per column: max |J − J_fd| / max |J_fd| over the whole Jacobian, at a random point."""
    rng = np.random.default_rng(seed)
    meas = simulate_measurements(mech, sample_actuators(mech, n_poses, rng), None, rng)
    prob = CalibrationProblem(mech, params, meas, noise={"position": 0.01, "orientation": 0.01})
    prior = joint_term_prior(params)
    scale = np.where(np.isnan(prior), 1e-4, prior)
    x = rng.normal(0.0, 1.0, len(params)) * scale
    _, J, _ = prob.evaluate(x)
    J_fd = np.empty_like(J)
    for k in range(len(params)):
        e = np.zeros(len(params))
        e[k] = 1e-3 * scale[k]
        hi, _, _ = prob.evaluate(x + e, jacobian=False)
        lo, _, _ = prob.evaluate(x - e, jacobian=False)
        J_fd[:, k] = (hi - lo) / (2 * e[k])
    floor = np.abs(J_fd * scale).max()  # a column's size as the pose change per prior σ
    return np.abs(J - J_fd).max(axis=0) * scale / floor


def test_terms_are_parameters_with_units(ur5):
    params = with_joint_terms(ur5, parameters(ur5, "base"), ALL)
    assert params.label == "base+compliance+gain+harmonics"
    terms = [params.names[k] for k in params.joint_terms]
    assert len(terms) == 6 * (1 + 1 + 4)
    assert "shoulder_lift_joint.compliance" in terms and "wrist_3_joint.cos2" in terms
    k = params.index("elbow_joint.compliance")
    assert params.units[k] == "rad/(N·m)"
    assert params.units[params.index("elbow_joint.gain")] == "1"
    # a joint term does not move the geometry
    x = np.zeros(len(params))
    x[params.joint_terms] = 1e-3
    moved = params.apply(ur5, x)
    q = ur5.q_home
    assert np.allclose(moved.frame_placement(q).homogeneous, ur5.frame_placement(q).homogeneous)
    # the names round-trip through parameters()
    again = parameters(ur5, list(params.names))
    assert again == params


def test_basis_matches_its_definition(ur5):
    params = with_joint_terms(ur5, parameters(ur5, ["elbow_joint.offset"]), ALL)
    rng = np.random.default_rng(3)
    rows = sample_actuators(ur5, 5, rng)
    B = joint_term_basis(ur5, params, rows)
    e = ur5.actuated.index("elbow_joint")
    assert np.allclose(B[:, e, params.index("elbow_joint.gain")], rows[:, e])
    assert np.allclose(B[:, e, params.index("elbow_joint.cos2")], np.cos(2 * rows[:, e]))
    assert np.all(B[:, :, params.index("elbow_joint.offset")] == 0)
    # compliance: the gravity torque, i.e. the derivative of the potential energy
    import pinocchio as pin

    k = params.index("elbow_joint.compliance")
    model, data = ur5.model, ur5.model.createData()
    for row, b in zip(rows, B[:, e, k], strict=True):
        q = ur5.with_actuators(ur5.q_home, row)
        v = np.zeros(model.nv)
        v[model.idx_vs[model.getJointId("elbow_joint")]] = 1.0
        h = 1e-6
        up = pin.computePotentialEnergy(model, data, pin.integrate(model, q, h * v))
        dn = pin.computePotentialEnergy(model, data, pin.integrate(model, q, -h * v))
        assert b == pytest.approx((up - dn) / (2 * h), rel=1e-6, abs=1e-9)
    assert np.max(np.abs(B[:, e, k])) > 1.0  # a real load [N·m]


def test_jacobian_matches_finite_differences_serial(ur5):
    params = with_joint_terms(ur5, parameters(ur5, "base"), ALL)
    err = _fd_errors(ur5, params, 12, seed=0)
    assert err.max() < 1e-6, params.names[int(np.argmax(err))]


@pytest.mark.parametrize("machine", ["fivebar", "rpr3"])
def test_jacobian_matches_finite_differences_closed_loops(machine):
    """Gain and harmonics act on the actuators of a parallel machine too (closure included)."""
    mech = load_mechanism(MACHINES / machine)
    kinds = (
        ("gain", "harmonics")
        if any(mech.tree.joints[a].type in ("revolute", "continuous") for a in mech.actuated)
        else ("gain",)
    )
    params = with_joint_terms(mech, parameters(mech, "base"), kinds)
    err = _fd_errors(mech, params, 8, seed=1)
    assert err.max() < 1e-5, params.names[int(np.argmax(err))]


def test_bad_requests_are_specific(ur5, stewart):
    with pytest.raises(ParameterError, match="geometric"):
        split_model("compliance")
    with pytest.raises(ParameterError, match="valid: geometric, .*compliance"):
        split_model("geometric+backlash")
    assert split_model("geometric+gain+gain") == ("gain",)
    fivebar = load_mechanism(MACHINES / "fivebar")  # no link masses
    with pytest.raises(ParameterError, match="no link masses"):
        with_joint_terms(fivebar, parameters(fivebar, "base"), ["compliance"])
    with pytest.raises(ParameterError, match="actuated"):
        parameters(ur5, ["ee_fixed_joint.gain"])


def test_pose_by_pose_sensitivity_refuses_joint_terms(ur5):
    """The single-pose path has no joint-term columns: it says so instead of zeros."""
    from pincal.sensitivity import pose_sensitivity, sensitivities_batch

    params = parameters(ur5, "base+gain")
    with pytest.raises(ParameterError, match="sensitivities_batch"):
        pose_sensitivity(ur5, params, ur5.q_home)
    q = ur5.with_actuators(ur5.q_home, np.full(6, 0.3))  # gain columns vanish at q = 0
    J = sensitivities_batch(ur5, params, q[None]).jacobian
    assert np.all(np.linalg.norm(J[0][:, params.joint_terms], axis=0) > 0)
