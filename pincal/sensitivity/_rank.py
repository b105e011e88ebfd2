"""The one numerical-rank rule of sensitivity and design, and the solve built on it.

A matrix with singular values σ1 ≥ σ2 ≥ … has numerical rank

    r = #{ i : σi > rtol · σ1 }      (r = 0 when σ1 = 0),

with one default relative tolerance :data:`RANK_RTOL` = 1e-8. Every rank decision
in :mod:`pincal.sensitivity` and :mod:`pincal.design` (identifiability, base
selection, observability indices, Cramér–Rao bounds, the closure solve of the
identification Jacobian) uses this rule; only the tolerance may be passed
explicitly (the closure solve uses the mechanism's own ``options.rcond``).

The rank of an *identification Jacobian* (columns = parameters in m and rad) is
decided by :func:`jacobian_rank` alone: its columns scaled to unit norm first
(:func:`unit_columns`), so the units and lever arms of the parameters do not bias it,
then the rule above. ``info``, the presets, pose selection and its Cramér–Rao bound,
and identification all call it, so one command cannot call unidentifiable what
another calls identifiable on the same rows.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pincal.errors import PincalError

__all__ = [
    "RANK_RTOL",
    "RangeSolver",
    "full_jacobian_ranks",
    "jacobian_rank",
    "numerical_rank",
    "numerical_ranks",
    "unit_columns",
]

RANK_RTOL: float = 1e-8
"""Default relative singular-value threshold of :func:`numerical_rank`."""


def _check_rtol(rtol: float) -> float:
    if not (np.isfinite(rtol) and 0.0 <= rtol < 1.0):
        raise PincalError(
            f"rank tolerance rtol must be a relative threshold in [0, 1); got {rtol!r}. "
            f"The default is {RANK_RTOL:g}."
        )
    return float(rtol)


def numerical_ranks(sigma: ArrayLike, rtol: float = RANK_RTOL) -> NDArray[np.int_]:
    """Numerical rank of each row of a batch of singular values: count of σi > rtol·σ1.

    Args:
        sigma: singular values (B, k), one matrix per row, any order within a row.
        rtol: relative threshold in [0, 1) (default :data:`RANK_RTOL` = 1e-8).

    Returns:
        Ranks (B,) (0 for an all-zero row).

    Raises:
        PincalError: ``rtol`` is not in [0, 1) or ``sigma`` is not 2-D.
    """
    s = np.asarray(sigma, dtype=float)
    rtol = _check_rtol(rtol)
    if s.ndim != 2:
        raise PincalError(f"sigma must be a batch (B, k) of singular values; got {s.shape}")
    if s.shape[1] == 0:
        return np.zeros(s.shape[0], dtype=int)
    s1 = np.max(s, axis=1, keepdims=True)
    return np.where(s1[:, 0] > 0.0, np.count_nonzero(s > rtol * s1, axis=1), 0)


def numerical_rank(sigma: ArrayLike, rtol: float = RANK_RTOL) -> int:
    """Numerical rank from singular values: the count of σi > rtol·σ1.

    Args:
        sigma: singular values, shape (k,), in any order (the largest is σ1).
        rtol: relative threshold in [0, 1) (default :data:`RANK_RTOL` = 1e-8).

    Returns:
        The rank r, 0 ≤ r ≤ k (0 for an empty or all-zero ``sigma``).

    Raises:
        PincalError: ``rtol`` is not in [0, 1).
    """
    return int(numerical_ranks(np.asarray(sigma, dtype=float).reshape(1, -1), rtol)[0])


def unit_columns(J: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Columns of J (rows, n) scaled to unit Euclidean norm, and the norms (n,).

    A column whose norm is at most 1e-12 of the largest counts as zero (the parameter
    has no effect): it is zeroed and its norm reported as 0.
    """
    a = np.asarray(J, dtype=float)
    scale = np.linalg.norm(a, axis=0)
    scale[scale <= 1e-12 * max(float(scale.max(initial=0.0)), 1e-300)] = 0.0
    scaled = a / np.where(scale > 0, scale, 1.0)
    scaled[:, scale == 0] = 0.0
    return scaled, scale


def jacobian_rank(J: ArrayLike, rtol: float = RANK_RTOL) -> int:
    """The numerical rank of an identification Jacobian J (rows, n).

    The rank rule (:func:`numerical_rank`, σi > ``rtol``·σ1) on its unit-norm columns
    (:func:`unit_columns`): the units (m, rad) and lever arms do not bias it.
    """
    scaled, _ = unit_columns(J)
    if scaled.size == 0:
        return 0
    return numerical_rank(np.linalg.svd(scaled, compute_uv=False), rtol)


def full_jacobian_ranks(
    J: ArrayLike, sigma: ArrayLike, rtol: float = RANK_RTOL
) -> NDArray[np.bool_]:
    """Whether each Jacobian of a batch has full column rank by :func:`jacobian_rank`.

    Exactly ``jacobian_rank(J[b], rtol) == n`` for each b, without the SVD of the
    unit-column matrix where the singular values of the unscaled one already decide:
    with column norms c, σn(J)/c_max ≤ σn(JD) ≤ σn(J)/c_min and σ1(J)/c_max ≤ σ1(JD) ≤
    σ1(J)/c_min (D = diag(1/c)), so only designs inside that band are decomposed again.

    Args:
        J: Jacobians (B, rows, n) (any row scaling; the columns are normalised here).
        sigma: singular values (B, min(rows, n)) of the unscaled J, descending.
        rtol: relative threshold (default :data:`RANK_RTOL`).

    Returns:
        (B,) booleans.
    """
    a = np.asarray(J, dtype=float)
    s = np.asarray(sigma, dtype=float)
    rtol = _check_rtol(rtol)
    B, rows, n = a.shape
    if rows < n or n == 0:
        return np.zeros(B, dtype=bool)
    c = np.linalg.norm(a, axis=1)  # (B, n) column norms
    c_max = c.max(axis=1)
    c_min = c.min(axis=1)
    alive = (c_min > 1e-12 * np.maximum(c_max, 1e-300)) & (s[:, 0] > 0.0)
    out = np.zeros(B, dtype=bool)
    safety = 1.0 + 1e-6  # rounding of the two decompositions
    with np.errstate(divide="ignore", invalid="ignore"):
        low = s[:, n - 1] / c_max / (s[:, 0] / c_min)  # a lower bound of σn(JD)/σ1(JD)
        high = s[:, n - 1] / c_min / (s[:, 0] / c_max)  # an upper bound
    sure = alive & (low > rtol * safety)
    out[sure] = True
    band = np.flatnonzero(alive & ~sure & (high * safety > rtol))
    for b in band:
        out[b] = jacobian_rank(a[b], rtol) == n
    return out


@dataclass(frozen=True, eq=False)
class RangeSolver:
    """One truncated-SVD factorisation of A (rows, cols), applied to many right-hand sides.

    ``A = U S Vᵀ`` with the singular values above the rank rule kept
    (:func:`numerical_rank`), so redundant rows (over-constrained loops) and rank
    loss are harmless: :meth:`solve` returns the minimum-norm least-squares
    solution A⁺B for all columns of B at once, and :meth:`out_of_range` measures
    how far each column of B lies outside the range of A (the part no X can
    reproduce).

    Attributes:
        u: left singular vectors of the range, (rows, r).
        s: kept singular values, (r,).
        vt: right singular vectors of the range, (r, cols).
        rank: r.
    """

    u: NDArray[np.float64]
    s: NDArray[np.float64]
    vt: NDArray[np.float64]
    rank: int

    @classmethod
    def factor(cls, A: ArrayLike, rtol: float = RANK_RTOL) -> RangeSolver:
        """Factor A (rows, cols) once with the rank rule ``σ > rtol·σ1``."""
        a = np.asarray(A, dtype=float)
        if a.ndim != 2:
            raise PincalError(f"RangeSolver needs a 2-D matrix; got shape {a.shape}")
        if a.size == 0:
            return cls(np.zeros((a.shape[0], 0)), np.zeros(0), np.zeros((0, a.shape[1])), 0)
        u, s, vt = np.linalg.svd(a, full_matrices=False)
        r = numerical_rank(s, rtol)
        return cls(u[:, :r], s[:r], vt[:r], r)

    def solve(self, B: ArrayLike) -> NDArray[np.float64]:
        """Minimum-norm least-squares X = A⁺B, B (rows, k) → X (cols, k) (or (rows,) → (cols,))."""
        b = np.asarray(B, dtype=float)
        return self.vt.T @ ((self.u.T @ b) / (self.s[:, None] if b.ndim == 2 else self.s))

    def out_of_range(self, B: ArrayLike) -> NDArray[np.float64]:
        """Norm of each column of B outside range(A), ‖(I − U Uᵀ) b_k‖, shape (k,)."""
        b = np.asarray(B, dtype=float).reshape(self.u.shape[0], -1)
        if self.rank == self.u.shape[0]:  # full row rank: the range is everything
            return np.zeros(b.shape[1])
        return np.linalg.norm(b - self.u @ (self.u.T @ b), axis=0)
