"""Cramér–Rao bound of a whitened Jacobian and the accuracies it predicts.

Plain numpy: an identification Jacobian is a stacked array (rows, n) or blocks
(m, k, n) (see :mod:`pincal.design._indices`).
"""

from __future__ import annotations

import logging
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pincal.design._indices import as_stacked
from pincal.errors import PincalError, UnidentifiableError
from pincal.sensitivity import jacobian_rank, unit_columns

__all__ = ["crb_covariance", "predicted_std", "predicted_validation_rms"]

_log = logging.getLogger(__name__)


def crb_covariance(
    J_weighted: ArrayLike,
    *,
    allow_rank_deficient: bool = False,
    names: Sequence[str] | None = None,
) -> NDArray[np.float64]:
    """Cramér–Rao bound (JᵀJ)⁻¹ of a noise-whitened identification Jacobian.

    For unbiased estimation with rows whitened by the measurement noise
    (:func:`weight_rows`), every estimator has Cov ⪰ (JᵀΣ⁻¹J)⁻¹.

    Args:
        J_weighted: whitened Jacobian (rows, n) or (m, k, n).
        allow_rank_deficient: if True a rank-deficient J gives the pseudo-inverse
            (the bound for the estimable combinations only); else it is an error. The
            rank is :func:`pincal.sensitivity.jacobian_rank` (unit columns, then
            σi > 1e-8·σ1), the one rank decision of every command.
        names: parameter names (n,) for the error message.

    Returns:
        Covariance (n, n) in the (scaled) units of the columns of J.

    Raises:
        UnidentifiableError: J has rank < n and ``allow_rank_deficient`` is False.
    """
    arr = as_stacked(J_weighted, "J_weighted")
    n = arr.shape[1]
    scaled, scale = unit_columns(arr)
    rank = jacobian_rank(arr)  # the one rank decision (unit columns, σ > 1e-8·σ1)
    if rank == n:
        # (JᵀJ)⁻¹ = D⁻¹ (JsᵀJs)⁻¹ D⁻¹ with Js = J D⁻¹: the unit columns keep a Jacobian
        # of mixed units (m, rad) and lever arms well conditioned
        _, s, vt = np.linalg.svd(scaled, full_matrices=False)
        v = vt.T / scale[:, None]
        return (v / s**2) @ v.T
    _, s, vt = np.linalg.svd(arr, full_matrices=True)
    s_full = np.concatenate([s, np.zeros(n - s.size)]) if s.size < n else s
    null = vt[rank:]
    involved = np.flatnonzero(np.max(np.abs(null), axis=0) > 1e-8)
    labels = [names[int(i)] for i in involved] if names is not None else [str(i) for i in involved]
    if not allow_rank_deficient:
        raise UnidentifiableError(
            f"Jacobian has rank {rank} < {n} parameters; the unobservable directions involve "
            f"parameters {', '.join(labels)}",
            names=labels,
        )
    _log.warning("CRB of a rank-deficient Jacobian (rank %d < %d): pseudo-inverse", rank, n)
    v = vt[:rank].T
    return (v / s_full[:rank] ** 2) @ v.T


def predicted_std(cov: ArrayLike) -> NDArray[np.float64]:
    """Standard deviations sqrt(diag(cov)), shape (n,)."""
    c = np.asarray(cov, dtype=float)
    if c.ndim != 2 or c.shape[0] != c.shape[1]:
        raise PincalError(f"covariance must be square (n, n); got {c.shape}")
    return np.sqrt(np.clip(np.diag(c), 0.0, None))


def predicted_validation_rms(J_val: ArrayLike, cov: ArrayLike) -> float:
    """Expected RMS of the prediction error over validation rows.

    If the identified parameters have covariance ``cov``, the error they cause
    at validation rows with Jacobian J_val has expected mean square
    tr(J_val · cov · J_valᵀ)/rows; this returns its square root (in the units
    of the rows of J_val).

    Args:
        J_val: validation Jacobian (rows, n) or (m, k, n), unweighted.
        cov: parameter covariance (n, n).
    """
    jv = as_stacked(J_val, "J_val")
    c = np.asarray(cov, dtype=float)
    if c.shape != (jv.shape[1], jv.shape[1]):
        raise PincalError(f"cov must be ({jv.shape[1]}, {jv.shape[1]}); got {c.shape}")
    mean_square = np.einsum("ij,jk,ik->", jv, c, jv) / jv.shape[0]
    return float(np.sqrt(max(mean_square, 0.0)))
