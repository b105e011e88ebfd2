"""The analytic identification Jacobian against central finite differences."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from pincal.model import parameters
from pincal.sensitivity import identification_jacobian


def measured(mech, q_act_rows, reference_rotations):
    """Measured quantity [p; log3(R_ref^T R)] stacked over poses, by re-solving the loops."""
    out = []
    for row, R_ref in zip(q_act_rows, reference_rotations, strict=True):
        T = mech.forward(row)
        out.append(np.concatenate([T.translation, pin.log3(R_ref.T @ T.rotation)]))
    return np.concatenate(out)


def fd_jacobian(mech, params, q_act_rows, values, h=1e-6):
    at = params.apply(mech, values)
    R_ref = [at.forward(r).rotation for r in q_act_rows]
    cols = []
    for k in range(len(params)):
        e = np.zeros(len(params))
        e[k] = h
        plus = measured(params.apply(mech, values + e), q_act_rows, R_ref)
        minus = measured(params.apply(mech, values - e), q_act_rows, R_ref)
        cols.append((plus - minus) / (2 * h))
    return np.stack(cols, axis=1)


# "full" (78 parameters, ~20 s) in the slow lane; the fast lane checks stewart42
@pytest.mark.parametrize("preset", ["stewart42", pytest.param("full", marks=pytest.mark.slow)])
@pytest.mark.parametrize("at_zero", [True, False])
def test_analytic_matches_central_differences(stewart, stewart_poses, preset, at_zero):
    params = parameters(stewart, preset)
    rng = np.random.default_rng(5)
    values = np.zeros(len(params)) if at_zero else rng.normal(0, 1e-3, len(params))
    rows = stewart_poses[:2]
    J = identification_jacobian(stewart, params, rows, values)
    J_fd = fd_jacobian(stewart, params, rows, values)
    assert J.shape == (12, len(params))
    assert np.max(np.abs(J - J_fd)) <= 1e-6 * np.max(np.abs(J))


def test_measured_frame_parameter_has_direct_effect(stewart, stewart_poses):
    """A twist of the measured frame's own origin moves it by exactly that twist."""
    params = parameters(stewart, ["effector_joint.tz", "effector_joint.rx"])
    J = identification_jacobian(stewart, params, stewart_poses[:1])
    R = stewart.frame_placement(stewart.configuration(stewart_poses[0]), "effector").rotation
    assert np.allclose(J[:3, 0], R[:, 2], atol=1e-12)
    assert np.allclose(J[3:, 1], [1, 0, 0], atol=1e-12)


@pytest.mark.parametrize(
    ("model", "preset"),
    [("pkm5", "hinges24"), ("wedge3", "patent"), ("hexaslide_6pus", "pus54"), ("aacmm", "dh")],
)
def test_partial_closures_and_components_match_central_differences(model, preset):
    """Partial closures ([y, z], [x, z]), component subsets and serial chains."""
    from pincal.model import load_mechanism, sample_actuators

    mech = load_mechanism(model)
    params = parameters(mech, preset)
    rows = sample_actuators(mech, 2, np.random.default_rng(4))
    values = np.random.default_rng(6).normal(0, 2e-4, len(params))
    J = identification_jacobian(
        mech, params, rows, values, components=("x", "y", "z", "rx", "ry", "rz")
    )
    J_fd = fd_jacobian(mech, params, rows, values)
    assert np.max(np.abs(J - J_fd)) <= 1e-6 * np.max(np.abs(J))


@pytest.mark.parametrize("model", ["pkm5", "wedge3", "hexaslide_6pus", "aacmm"])
def test_inverse_then_forward_round_trip(model):
    from pincal.model import load_mechanism, sample_actuators

    mech = load_mechanism(model)
    for row in sample_actuators(mech, 3, np.random.default_rng(2)):
        T = mech.forward(row)
        q_act = mech.inverse(T, q_guess=mech.q_home)
        T2 = mech.forward(q_act)
        assert np.max(np.abs(T2.translation - T.translation)) <= 1e-10
