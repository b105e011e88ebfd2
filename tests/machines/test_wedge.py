"""Tests of the closed-form wedge kinematics, error matrices and URDF (pincal.machines)."""

from __future__ import annotations

import numpy as np
import pytest

from pincal.errors import (
    ClosureError,
    ParameterError,
)
from pincal.machines import (
    PATENT_ERROR_NAMES,
    WedgeGeometry,
    wedge_constraint_jacobians,
    wedge_constraints,
    wedge_error_matrix,
    wedge_forward,
    wedge_global_sensitivity,
    wedge_inverse,
    wedge_patent_error_matrix,
    wedge_workspace_grid,
)

NOMINAL = WedgeGeometry.nominal()
# an asymmetric, offset geometry so that no term hides behind a symmetry
SKEWED = WedgeGeometry(l1=0.1, l2=0.12, k1=0.18, k2=0.27, dq0=1.3e-3, dq1=-2.1e-3, dq2=0.7e-3)


def _random_poses(rng: np.random.Generator, m: int = 200) -> np.ndarray:
    lo = np.array([-0.05, -0.004, -0.03])
    hi = -lo
    return rng.uniform(lo, hi, size=(m, 3))


@pytest.mark.parametrize("geom", [NOMINAL, SKEWED])
def test_round_trips(geom: WedgeGeometry) -> None:
    rng = np.random.default_rng(0)
    poses = _random_poses(rng)
    q = wedge_inverse(poses, geom)
    np.testing.assert_allclose(wedge_forward(q, geom), poses, rtol=0, atol=1e-12)
    q_rand = rng.uniform(-0.02, 0.02, size=(200, 3))
    np.testing.assert_allclose(
        wedge_inverse(wedge_forward(q_rand, geom), geom), q_rand, rtol=0, atol=1e-12
    )
    # single-pose shapes
    assert wedge_forward(q[0], geom).shape == (3,)
    assert wedge_inverse(poses[0], geom).shape == (3,)


@pytest.mark.parametrize("geom", [NOMINAL, SKEWED])
def test_forward_solution_is_geometric(geom: WedgeGeometry) -> None:
    """Bar ends lie on the wedge wall lines, computed without the constraint function."""
    rng = np.random.default_rng(1)
    q = rng.uniform(-0.02, 0.02, size=(100, 3))
    pose = wedge_forward(q, geom)
    np.testing.assert_allclose(wedge_constraints(q, pose, geom), 0.0, atol=1e-14)
    x, z, a = pose.T
    Q = q + np.array([geom.dq0, geom.dq1, geom.dq2])
    np.testing.assert_allclose(x, Q[:, 0], atol=1e-15)
    end1 = np.stack([x - geom.l1 * np.cos(a), z - geom.l1 * np.sin(a)], -1)
    end2 = np.stack([x + geom.l2 * np.cos(a), z + geom.l2 * np.sin(a)], -1)
    ref1 = np.stack([Q[:, 1] - geom.l1, 0 * x], -1)
    ref2 = np.stack([Q[:, 2] + geom.l2, 0 * x], -1)
    # wall 1 direction (1, -k1), wall 2 direction (1, k2): cross product of (end - ref) with it
    d1 = end1 - ref1
    d2 = end2 - ref2
    np.testing.assert_allclose(d1[:, 0] * -geom.k1 - d1[:, 1], 0.0, atol=1e-15)
    np.testing.assert_allclose(d2[:, 0] * geom.k2 - d2[:, 1], 0.0, atol=1e-15)
    # physical branch: bar not turned over
    assert np.all(np.cos(a) > 0.9)


def test_home_pose_and_lift() -> None:
    g = NOMINAL
    np.testing.assert_allclose(wedge_forward(np.zeros(3), g), 0.0, atol=1e-16)
    # wedges moved towards each other by d lift the bar by k d, level
    d = 0.01
    np.testing.assert_allclose(
        wedge_forward(np.array([0.0, d, -d]), g), [0.0, g.k1 * d, 0.0], atol=1e-15
    )
    # wedge 1 alone moved by d: end 1 rises by k d, centre by k d / 2, α = -asin(k d / 2l)
    pose = wedge_forward(np.array([0.0, d, 0.0]), g)
    z1 = pose[1] - g.l1 * np.sin(pose[2])
    z2 = pose[1] + g.l2 * np.sin(pose[2])
    # end 2 stays on its unmoved wall; it only slides by the second-order x shift l2 (cosα − 1)
    assert z2 == pytest.approx(g.k2 * g.l2 * (np.cos(pose[2]) - 1.0), abs=1e-15)
    assert pose[2] == pytest.approx(-np.arcsin(g.k1 * d / (2 * g.l1)), rel=1e-3)
    assert z1 == pytest.approx(g.k1 * d, rel=1e-3)
    assert pose[2] < 0.0


def _central_diff(fun, x0: np.ndarray, h: float) -> np.ndarray:
    cols = []
    for i in range(x0.size):
        e = np.zeros_like(x0)
        e[i] = h
        cols.append((fun(x0 + e) - fun(x0 - e)) / (2 * h))
    return np.stack(cols, axis=-1)


@pytest.mark.parametrize("geom", [NOMINAL, SKEWED])
def test_constraint_jacobians_vs_finite_differences(geom: WedgeGeometry) -> None:
    rng = np.random.default_rng(2)
    q = rng.uniform(-0.03, 0.03, size=3)
    pose = np.array([0.01, 0.003, 0.2])  # away from the solution: Jacobians hold anywhere
    jac = wedge_constraint_jacobians(q, pose, geom)
    p0 = geom.as_vector()
    fd_pose = _central_diff(lambda p: wedge_constraints(q, p, geom), pose, 1e-6)
    fd_q = _central_diff(lambda qq: wedge_constraints(qq, pose, geom), q, 1e-6)
    fd_par = _central_diff(
        lambda p: wedge_constraints(q, pose, WedgeGeometry.from_vector(p)), p0, 1e-7
    )
    np.testing.assert_allclose(jac.d_pose, fd_pose, atol=1e-9)
    np.testing.assert_allclose(jac.d_q, fd_q, atol=1e-9)
    np.testing.assert_allclose(jac.d_params, fd_par, atol=1e-9)
    # batched evaluation agrees with single evaluation
    jb = wedge_constraint_jacobians(np.stack([q, q]), np.stack([pose, pose]), geom)
    np.testing.assert_array_equal(jb.d_params[1], jac.d_params)


@pytest.mark.parametrize("geom", [NOMINAL, SKEWED])
def test_error_matrix_vs_finite_differences_of_forward(geom: WedgeGeometry) -> None:
    q = wedge_inverse(np.array([0.02, -0.002, 0.015]), geom)
    J = wedge_error_matrix(q, geom)
    fd = _central_diff(
        lambda p: wedge_forward(q, WedgeGeometry.from_vector(p)), geom.as_vector(), 1e-7
    )
    np.testing.assert_allclose(J, fd, atol=1e-8)


def test_patent_error_matrix_layout() -> None:
    rng = np.random.default_rng(3)
    q = wedge_inverse(_random_poses(rng, 20), SKEWED)
    Jp = wedge_patent_error_matrix(q, SKEWED)
    J = wedge_error_matrix(q, SKEWED)
    assert Jp.shape == (20, 3, 12)
    np.testing.assert_array_equal(Jp[:, :, 1:4], 0.0)
    idx = {n: i for i, n in enumerate(PATENT_ERROR_NAMES)}
    par = {n: i for i, n in enumerate(WedgeGeometry.PARAMETER_NAMES)}
    np.testing.assert_allclose(
        Jp[:, :, idx["f0.dq0"]] + Jp[:, :, idx["f1.dq0"]] + Jp[:, :, idx["f2.dq0"]],
        J[:, :, par["dq0"]],
        atol=1e-15,
    )
    for pn, name in [("f1.dq1", "dq1"), ("f1.l1", "l1"), ("f1.k1", "k1")]:
        np.testing.assert_allclose(Jp[:, :, idx[pn]], J[:, :, par[name]], atol=1e-15)
    for pn, name in [("f2.dq2", "dq2"), ("f2.l2", "l2"), ("f2.k2", "k2")]:
        np.testing.assert_allclose(Jp[:, :, idx[pn]], J[:, :, par[name]], atol=1e-15)
    # hand-derived values at the home pose of a symmetric machine (see module docstring)
    g = NOMINAL
    J0 = wedge_patent_error_matrix(np.zeros(3), g)
    k, lb = g.k1, g.l1
    np.testing.assert_allclose(J0[:, idx["f0.dq0"]], [1.0, 0.0, 0.0], atol=1e-16)
    np.testing.assert_allclose(J0[:, idx["f1.dq0"]], [0.0, -k / 2, k / (2 * lb)], atol=1e-15)
    np.testing.assert_allclose(J0[:, idx["f2.dq0"]], [0.0, k / 2, k / (2 * lb)], atol=1e-15)


def test_global_sensitivity_groups() -> None:
    """Symmetric machine + α-symmetric workspace: the patent's equal-sensitivity pairs."""
    poses = wedge_workspace_grid((-0.05, 0.05), (-0.002, 0.002), (-0.01, 0.01), n=5)
    s = wedge_global_sensitivity(NOMINAL, poses)
    idx = {n: i for i, n in enumerate(s.names)}
    assert s.n_samples == 125
    for a, b in [
        ("f1.dq0", "f2.dq0"),
        ("f1.dq1", "f2.dq2"),
        ("f1.l1", "f2.l2"),
        ("f1.k1", "f2.k2"),
    ]:
        assert s.position[idx[a]] == pytest.approx(s.position[idx[b]], rel=1e-9)
        assert s.orientation[idx[a]] == pytest.approx(s.orientation[idx[b]], rel=1e-9)
        assert s.position[idx[a]] > 0.0
    # f0.dq0 maps 1:1 onto x only
    assert s.position[idx["f0.dq0"]] == pytest.approx(1.0)
    assert s.orientation[idx["f0.dq0"]] == pytest.approx(0.0, abs=1e-15)
    # the symmetry is broken by an asymmetric machine: the check above can fail
    s2 = wedge_global_sensitivity(SKEWED, poses)
    assert (
        abs(s2.position[idx["f1.k1"]] - s2.position[idx["f2.k2"]])
        > 1e-3 * s2.position[idx["f1.k1"]]
    )
    s7 = wedge_global_sensitivity(NOMINAL, poses, columns="parameters")
    assert s7.names == WedgeGeometry.PARAMETER_NAMES


def test_errors() -> None:
    with pytest.raises(ClosureError):
        wedge_forward(np.array([0.0, 1.5, 1.5]), NOMINAL)
    with pytest.raises(ParameterError):
        wedge_forward(np.zeros(4), NOMINAL)
    with pytest.raises(ParameterError):
        WedgeGeometry(l1=0.1, l2=0.1, k1=0.0, k2=0.2)
    with pytest.raises(ParameterError):
        WedgeGeometry.from_vector(np.zeros(6))
    with pytest.raises(ParameterError):
        wedge_global_sensitivity(NOMINAL, np.zeros((2, 3)), columns="bad")  # type: ignore[arg-type]
