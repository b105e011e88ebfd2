"""Outlying poses by deletion: one bad pose is named as one bad pose.

A least-squares fit spreads a gross error over every pose, so thresholds on the fitted
residuals name good poses (or all of them) for one bad one. Here each pose is judged
by the residual it would have if it had been left out of the (linearised) fit — its
*deleted* residual — against the scale of the other poses:

    d_i = r_iᵀ (I − H_ii)⁻¹ r_i,   s_(i)² = (RSS − d_i) / (ν − k),
    F_i = d_i / (k s_(i)²) ~ F(k, ν − k) for a pose that fits,

r_i the k whitened residuals of pose i, H_ii its k×k block of the hat matrix and ν the
redundancy. The pose of largest F_i is named when F_i exceeds the Bonferroni bound of
family-wise risk ``risk`` over the m poses; it is then removed, the linearised fit
repeated without it, and the search continues (backward deletion), up to ``cap`` poses.
The test is scale-free: it needs no declared noise and an inflated σ estimate cannot
hide an outlier.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["column_basis", "deletion_outliers"]

_MIN_EIG = 0.05  # (I − H_ii) eigenvalues floored: a pose that alone fixes a direction



def _f_isf(q: float, d1: float, d2: float) -> float:
    """The F(d1, d2) quantile exceeded with probability q (scipy.stats: imported here)."""
    from scipy import stats

    return float(stats.f.isf(q, d1, d2))

def deletion_outliers(
    A: np.ndarray, z: np.ndarray, risk: float = 1e-3, cap: int | None = None
) -> tuple[tuple[int, ...], float]:
    """Poses named outliers by backward deletion of the largest deleted residual.

    Args:
        A: (m, k, p) whitened Jacobian of the fitted (and any nuisance) terms.
        z: (m, k) whitened residuals at the solution.
        risk: family-wise false-alarm probability over the m poses.
        cap: the search stops after naming ``cap + 1`` poses — more than ``cap``
            means the residuals are not noise plus a few outliers (default m // 4).

    Returns:
        (named pose indices, ascending, the first bound as a normalised pose
        residual √(k·F_crit)); ``((), nan)`` when the poses leave too little redundancy.
    """
    m, k = z.shape
    p = A.shape[2]
    cap = m // 4 if cap is None else cap
    keep = np.ones(m, dtype=bool)
    named: list[int] = []
    bound = float("nan")
    while True:
        rows = np.flatnonzero(keep)
        Ak = A[rows].reshape(-1, p)
        U = column_basis(Ak)
        nu = rows.size * k - U.shape[1]
        if nu - k < 1:
            break
        zk = z[rows].ravel()
        r = (zk - U @ (U.T @ zk)).reshape(rows.size, k)
        Ui = U.reshape(rows.size, k, -1)
        M = np.eye(k)[None] - Ui @ np.swapaxes(Ui, 1, 2)
        vals, vecs = np.linalg.eigh(M)
        proj = np.einsum("nkj,nk->nj", vecs, r)
        d = np.sum(proj**2 / np.clip(vals, _MIN_EIG, None), axis=1)
        rss = float(np.sum(r**2))
        s2 = np.maximum(rss - d, 1e-300) / (nu - k)
        F = d / (k * s2)
        crit = _f_isf(risk / m, k, nu - k)
        if math.isnan(bound):
            bound = math.sqrt(k * crit)
        worst = int(np.argmax(F))
        if not F[worst] > crit:
            break
        named.append(int(rows[worst]))
        keep[rows[worst]] = False
        if len(named) > cap:
            break
    return tuple(sorted(named)), bound


def column_basis(A: np.ndarray) -> np.ndarray:
    """Orthonormal basis (N, r) of the column space of A (relative rank tolerance 1e-10)."""
    if A.size == 0:
        return np.zeros((A.shape[0], 0))
    U, s, _ = np.linalg.svd(A, full_matrices=False)
    r = int(np.sum(s > s[0] * 1e-10)) if s.size and s[0] > 0 else 0
    return U[:, :r]
