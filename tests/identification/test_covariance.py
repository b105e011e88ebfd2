"""The covariance from an SVD of the Jacobian equals (JᵀJ)⁻¹ where that is well posed,
stays positive semi-definite where it is not, and includes a prior as extra rows."""

from __future__ import annotations

import numpy as np

from pincal.identification._covariance import covariance_from_jacobian


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
