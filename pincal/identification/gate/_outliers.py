"""Outlying poses by deletion: one bad pose is named as one bad pose.

A least-squares fit spreads a gross error over every pose, so thresholds on the fitted
residuals name good poses (or all of them) for one bad one. Here each pose is judged
by the residual it would have if it had been left out of the (linearised) fit — its
*deleted* residual — against the scale of the other poses:

    d_i = r_iᵀ (I − H_ii)⁻¹ r_i,   s_(i)² = (RSS − d_i) / (ν − k),
    F_i = d_i / (k s_(i)²) ~ F(k, ν − k) for a pose that fits,

r_i the k whitened residuals of pose i, H_ii its k×k block of the hat matrix and ν the
redundancy. The pose of largest F_i is named when F_i exceeds the Bonferroni bound of
family-wise risk ``risk``/2 over the m poses; it is then removed, the linearised fit
repeated without it, and the search continues (backward deletion), up to ``cap`` poses.
The test is scale-free: it needs no declared noise and an inflated σ estimate cannot
hide an outlier.

Two outliers can mask each other: each inflates the scale s_(i) the other is judged
against (k = 1, ν = 22 as on a 60-reading ballbar file, two 50 σ readings: the largest
single F has median 27 against a bound of 34, below it in 69 % of linear-Gaussian
draws). When no single pose passes its bound, pairs S = {i, j} are
judged by the group statistic

    d_S = r_Sᵀ (I − H_SS)⁻¹ r_S,   s_(S)² = (RSS − d_S) / (ν − 2k),
    F_S = d_S / (2k s_(S)²) ~ F(2k, ν − 2k) for a pair that fits,

with the Bonferroni bound of risk ``risk``/2 over the m(m − 1)/2 pairs; the worst pair
past it is named (both poses) and the backward search continues — when each of its
poses, judged against s_(S) with the other deleted, (d_S − d_j) / (k s_(S)²), passes the
single bound: masking hides poses that stand out once their partner is gone, while a
pair carried by one pose just below its bound and a common one is no masked pair (and a
refit without it, its noise estimated without that pose, would see its partner larger
than it is). The two halves of the
risk bound a clean campaign's chance to name any pose by ``risk`` (measured on
linear-Gaussian draws at risk 0.05: 0.028–0.029, the single search alone at the full
risk 0.052–0.058; ``tests/identification/test_outlier_pairs.py``). All pairs are judged up to
``_PAIR_BUDGET`` pairs (≈ 316 poses); beyond, each of the ``_PAIR_BUDGET // n`` poses
of largest single d_i is paired with every other pose (the bound stays the one over all
pairs). That restriction finds a masked pair when one of its poses ranks among those
candidates — masking inflates the *scale*, not a bad pose's own deleted residual d_i
— but not two bad poses that hide behind each other (near-duplicate poses with the same
error, whose single d_i are both small).
"""

from __future__ import annotations

import math

import numpy as np

from pincal.identification._distributions import f_isf

__all__ = ["column_basis", "deletion_outliers", "refit_outliers"]

_MIN_EIG = 0.05  # (I − H_ii) eigenvalues floored: a pose that alone fixes a direction
_PAIR_BUDGET = 50_000  # pairs judged at most (all pairs up to ≈ 316 poses)
_CHUNK = 4096  # pairs judged at once (memory ≈ _CHUNK · (2k)² · 40 bytes + 2 · _CHUNK · k · p · 8)


def _deleted(M: np.ndarray, r: np.ndarray) -> np.ndarray:
    """rᵀ M⁻¹ r per batch, M (…, n, n) = I − H_SS with its eigenvalues floored at _MIN_EIG."""
    vals, vecs = np.linalg.eigh(M)
    proj = np.einsum("...kj,...k->...j", vecs, r)
    return np.sum(proj**2 / np.clip(vals, _MIN_EIG, None), axis=-1)


def _linearised(
    A: np.ndarray, z: np.ndarray, rows: np.ndarray
) -> tuple[np.ndarray, np.ndarray, int]:
    """Basis (n, k, q) of the fitted directions over ``rows``, residuals (n, k), redundancy."""
    n, k = rows.size, z.shape[1]
    U = column_basis(A[rows].reshape(-1, A.shape[2]))
    zk = z[rows].ravel()
    r = (zk - U @ (U.T @ zk)).reshape(n, k)
    return U.reshape(n, k, -1), r, n * k - U.shape[1]


def _worst_pair(
    Ui: np.ndarray, r: np.ndarray, d1: np.ndarray, nu: int, member: float
) -> tuple[int, int, float]:
    """The qualifying pair (i, j) of largest F_S, and its F_S (indices into the rows).

    A pair qualifies when each member, given the other deleted, passes ``member``;
    F_S = −inf when no pair does.

    Args:
        Ui: (n, k, q) basis of the fitted directions per pose.
        r: (n, k) residuals of the linearised fit.
        d1: (n,) single deleted residuals d_i (they also rank the candidates).
        nu: redundancy.
        member: bound of a member's F = (d_S − d_other) / (k s_(S)²).
    """
    n, k = r.shape
    if n * (n - 1) // 2 <= _PAIR_BUDGET:
        i, j = np.triu_indices(n, 1)
    else:  # the poses of largest single d_i, each with every other pose
        cand = np.argsort(-d1)[: max(1, _PAIR_BUDGET // n)]
        a, b = np.repeat(cand, n), np.tile(np.arange(n), cand.size)
        key = np.unique(np.minimum(a, b)[a != b] * n + np.maximum(a, b)[a != b])
        i, j = key // n, key % n
    Gd = Ui @ np.swapaxes(Ui, 1, 2)  # (n, k, k) diagonal blocks of the hat matrix
    rss, best = float(np.sum(r**2)), (-np.inf, 0, 0)
    for c in range(0, i.size, _CHUNK):
        a, b = i[c : c + _CHUNK], j[c : c + _CHUNK]
        X = np.einsum("paq,pbq->pab", Ui[a], Ui[b])  # H_ij
        top = np.concatenate([Gd[a], X], axis=2)
        H = np.concatenate([top, np.concatenate([np.swapaxes(X, 1, 2), Gd[b]], axis=2)], axis=1)
        d = _deleted(np.eye(2 * k)[None] - H, np.concatenate([r[a], r[b]], axis=1))
        s2 = np.maximum(rss - d, 1e-300) / (nu - 2 * k)
        FS = d / (2 * k * s2)
        FS[np.minimum(d - d1[b], d - d1[a]) / (k * s2) <= member] = -np.inf
        w = int(np.argmax(FS))
        if FS[w] > best[0]:
            best = (float(FS[w]), int(a[w]), int(b[w]))
    return best[1], best[2], best[0]


def deletion_outliers(
    A: np.ndarray, z: np.ndarray, risk: float = 1e-3, cap: int | None = None
) -> tuple[tuple[int, ...], float]:
    """Poses named outliers by backward deletion of the largest deleted residual.

    When no single pose passes its bound, the worst pair is judged (module docstring);
    a pair past its bound is named and the search goes on.

    Args:
        A: (m, k, p) whitened Jacobian of the fitted (and any nuisance) terms.
        z: (m, k) whitened residuals at the solution.
        risk: family-wise false-alarm probability over the m poses (and over the pairs).
        cap: the search stops after naming ``cap + 1`` poses — more than ``cap``
            means the residuals are not noise plus a few outliers (default m // 4).

    Returns:
        (named pose indices, ascending, the first bound as a normalised pose
        residual √(k·F_crit)); ``((), nan)`` when the poses leave too little redundancy.
    """
    m, k = z.shape
    cap = m // 4 if cap is None else cap
    keep = np.ones(m, dtype=bool)
    named: list[int] = []
    bound = float("nan")
    while len(named) <= cap:
        rows = np.flatnonzero(keep)
        Ui, r, nu = _linearised(A, z, rows)
        if nu - k < 1:
            break
        d = _deleted(np.eye(k)[None] - Ui @ np.swapaxes(Ui, 1, 2), r)
        s2 = np.maximum(float(np.sum(r**2)) - d, 1e-300) / (nu - k)
        F = d / (k * s2)
        crit = f_isf(risk / (2 * m), k, nu - k)
        if math.isnan(bound):
            bound = math.sqrt(k * crit)
        worst = int(np.argmax(F))
        if F[worst] > crit:
            out = [worst]
        elif nu - 2 * k >= 1 and rows.size >= 2:
            member = f_isf(risk / (2 * m), k, nu - 2 * k)
            i, j, FS = _worst_pair(Ui, r, d, nu, member)
            if not FS > f_isf(risk / (m * (m - 1)), 2 * k, nu - 2 * k):
                break
            out = [i, j]
        else:
            break
        named += [int(rows[o]) for o in out]
        keep[rows[out]] = False
    return tuple(sorted(named)), bound


def refit_outliers(
    A: np.ndarray,
    z: np.ndarray,
    named: tuple[int, ...],
    risk: float = 1e-3,
    cap: int | None = None,
) -> tuple[tuple[int, ...], float]:
    """The outlier test at a refit without ``named`` (the confirming test).

    The deletion search over all poses (:func:`deletion_outliers`), and the poses of
    ``named`` judged against the refit's own scale — the scale of the poses *outside*
    ``named`` — so that outliers masking each other cannot hide there either. For each
    i of S = ``named``: with the rest of S deleted,

        F_i = (d_S − d_(S∖i)) / (k s_(S)²) ~ F(k, ν − |S|k),   s_(S)² = (RSS − d_S) / (ν − |S|k),

    the deleted residual of i against the poses outside S, with the single search's
    bound (risk/2 over the m poses); the weakest member below it leaves S and the rest
    is judged again. A good pose the first (smeared) fit named has its ordinary deleted
    residual here and leaves S.

    Args:
        A: (m, k, p) whitened Jacobian at the refit, over all poses.
        z: (m, k) whitened residuals at the refit, over all poses.
        named: the poses the first test named (left out of the refit).
        risk: family-wise false-alarm probability (as in :func:`deletion_outliers`).
        cap: as in :func:`deletion_outliers`.

    Returns:
        (named poses: the search's and the confirmed members of ``named``, ascending;
        the search's first bound as a normalised pose residual).
    """
    found, bound = deletion_outliers(A, z, risk, cap)
    m, k = z.shape
    S = [int(i) for i in named]
    U, r, nu = _linearised(A, z, np.arange(m))
    U, r = U.reshape(m * k, -1), r.ravel()
    rss = float(np.sum(r**2))

    def d(group: list[int]) -> float:
        idx = (np.asarray(group)[:, None] * k + np.arange(k)).ravel()
        return float(_deleted(np.eye(idx.size) - U[idx] @ U[idx].T, r[idx]))

    while S and nu - len(S) * k >= 1:
        dof = nu - len(S) * k
        dS = d(S)
        s2 = max(rss - dS, 1e-300) / dof
        F = [(dS - (d(S[:n] + S[n + 1:]) if len(S) > 1 else 0.0)) / (k * s2)
             for n in range(len(S))]  # fmt: skip
        weakest = int(np.argmin(F))
        if F[weakest] > f_isf(risk / (2 * m), k, dof):
            break
        S.pop(weakest)
    else:
        S = []
    return tuple(sorted(set(found) | set(S))), bound


def column_basis(A: np.ndarray) -> np.ndarray:
    """Orthonormal basis (N, r) of the column space of A (relative rank tolerance 1e-10)."""
    if A.size == 0:
        return np.zeros((A.shape[0], 0))
    U, s, _ = np.linalg.svd(A, full_matrices=False)
    r = int(np.sum(s > s[0] * 1e-10)) if s.size and s[0] > 0 else 0
    return U[:, :r]
