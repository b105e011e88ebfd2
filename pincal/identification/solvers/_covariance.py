"""The parameter covariance from an SVD of the (whitened) Jacobian, not from inverting JᵀJ.

``(JᵀJ)⁺`` formed explicitly squares the condition number, and its pseudo-inverse can
carry round-off negative variances on ill-conditioned problems (NaN standard deviations).
Here ``A = [J; diag(prior)] = U S Vᵀ`` and ``cov = V S⁻² Vᵀ`` over the singular values
above the cut-off: symmetric positive semi-definite by construction, rank-revealing, with
the same cut-off as ``numpy.linalg.pinv(JᵀJ)`` (σ_i > sqrt(n·eps)·σ_1).
"""

from __future__ import annotations

import numpy as np

__all__ = ["covariance_from_jacobian", "fitted_covariance"]


def covariance_from_jacobian(J: np.ndarray, prior: np.ndarray | None = None) -> np.ndarray:
    """``(JᵀJ + diag(prior²))⁺`` (n, n) for a whitened Jacobian J (N, n).

    Args:
        J: (N, n) Jacobian of residuals divided by their σ.
        prior: (n,) prior weights 1/σ_prior (0 or None: no prior on that parameter).

    Returns:
        The covariance in J's units (multiply by the reduced χ² when σ was estimated).
    """
    A = np.asarray(J, dtype=float)
    n = A.shape[1]
    if prior is not None:
        A = np.vstack([A, np.diag(np.asarray(prior, dtype=float))])
    if n == 0 or A.shape[0] == 0:
        return np.zeros((n, n))
    _, s, Vt = np.linalg.svd(A, full_matrices=False)
    keep = s > np.sqrt(max(n, 1) * np.finfo(float).eps) * s[0] if s[0] > 0 else s > np.inf
    V = Vt[keep].T / s[keep]
    return V @ V.T


def fitted_covariance(
    Jf: np.ndarray,
    fitted: np.ndarray,
    n: int,
    prior: np.ndarray | None = None,
    scale: float = 1.0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The finishing step's covariance, shared by every identification.

    Args:
        Jf: (N, f) whitened Jacobian of the fitted unknowns, columns in ``fitted`` order.
        fitted: (f,) indices of the fitted unknowns; those below ``n`` are machine
            parameters, the others an instrument's own unknowns.
        n: the number of machine parameters.
        prior: (f,) prior weights of the fitted unknowns (see
            :func:`covariance_from_jacobian`).
        scale: factor of the covariance (the reduced χ² when σ was estimated).

    Returns:
        The marginal covariance of the fitted machine parameters (b, b) in index order,
        the (n,) mask of the fitted machine parameters, and the covariance of every
        fitted unknown (f, f) in index order.
    """
    fitted = np.asarray(fitted, dtype=int)
    order = np.argsort(fitted)
    cov = covariance_from_jacobian(Jf, prior)[np.ix_(order, order)] * scale
    f = fitted[order]
    machine = f < n
    mask = np.zeros(n, dtype=bool)
    mask[f[machine]] = True
    return cov[np.ix_(machine, machine)], mask, cov
