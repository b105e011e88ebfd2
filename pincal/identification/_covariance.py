"""The parameter covariance from an SVD of the (whitened) Jacobian, not from inverting JᵀJ.

``(JᵀJ)⁺`` formed explicitly squares the condition number, and its pseudo-inverse can
carry round-off negative variances on ill-conditioned problems (NaN standard deviations).
Here ``A = [J; diag(prior)] = U S Vᵀ`` and ``cov = V S⁻² Vᵀ`` over the singular values
above the cut-off: symmetric positive semi-definite by construction, rank-revealing, with
the same cut-off as ``numpy.linalg.pinv(JᵀJ)`` (σ_i > sqrt(n·eps)·σ_1).
"""

from __future__ import annotations

import numpy as np

__all__ = ["covariance_from_jacobian"]


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
