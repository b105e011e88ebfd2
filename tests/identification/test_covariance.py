"""The covariance from an SVD of the Jacobian equals (JᵀJ)⁻¹ where that is well posed,
stays positive semi-definite where it is not, and includes a prior as extra rows."""

from __future__ import annotations

import numpy as np

from pincal.identification.solvers._covariance import covariance_from_jacobian, fitted_covariance


def test_equals_the_inverse_normal_matrix_when_well_posed():
    J = np.random.default_rng(0).normal(size=(40, 6))
    np.testing.assert_allclose(covariance_from_jacobian(J), np.linalg.inv(J.T @ J), rtol=1e-10)


def test_prior_adds_its_information():
    J = np.random.default_rng(1).normal(size=(30, 4))
    w = np.array([0.0, 2.0, 0.5, 10.0])
    expected = np.linalg.inv(J.T @ J + np.diag(w**2))
    np.testing.assert_allclose(covariance_from_jacobian(J, w), expected, rtol=1e-10)


def test_ill_conditioned_never_gives_negative_variances():
    rng = np.random.default_rng(2)
    J = rng.normal(size=(50, 8))
    J[:, 7] = J[:, 6] * (1 + 1e-9) + J[:, 5] * 1e-12  # nearly dependent columns
    J[:, 3] *= 1e-9  # a barely excited direction
    cov = covariance_from_jacobian(J)
    assert np.all(np.diag(cov) >= 0)
    assert np.all(np.linalg.eigvalsh(0.5 * (cov + cov.T)) > -1e-12 * np.abs(cov).max())
    np.testing.assert_allclose(cov, cov.T, rtol=1e-12, atol=0)


def test_fitted_covariance_is_in_index_order_and_marginal():
    """The shared finishing step: columns given out of order, machine part marginal."""
    rng = np.random.default_rng(5)
    J = rng.normal(size=(40, 4))
    fitted = np.array([6, 2, 0, 5])  # n = 4 machine parameters: 2 and 0 are machine
    machine, mask, full = fitted_covariance(J, fitted, 4, scale=2.0)
    inv = np.linalg.inv(J.T @ J) * 2.0
    order = np.argsort(fitted)  # 0, 2, 5, 6
    np.testing.assert_allclose(full, inv[np.ix_(order, order)], rtol=1e-10)
    np.testing.assert_allclose(machine, inv[np.ix_([2, 1], [2, 1])], rtol=1e-10)
    assert mask.tolist() == [True, False, True, False]
