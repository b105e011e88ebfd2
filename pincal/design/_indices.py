"""Observability indices, Jacobian scaling and Cramér–Rao limits.

Everything here works on plain numpy arrays: an identification Jacobian is either
a stacked 2-D array ``(rows, n)`` or a block array ``(m, k, n)`` holding the ``k``
measurement rows of each of ``m`` poses for ``n`` parameters.

Observability indices (seed 000, eqs. 11–15, after Menq & Borm, Driels & Pathre,
Nahvi & Hollerbach, Sun & Hollerbach), from the singular values
σ1 ≥ … ≥ σL of the (scaled) Jacobian with L = n parameters and m poses:

=====  ==============================  ===========================================
name   definition                      meaning
=====  ==============================  ===========================================
O1     (σ1⋯σL)^(1/L) / √m              geometric mean; volume of the error ellipsoid
O2     σL / σ1                         inverse condition number
O3     σL                              smallest semi-axis
O4     σL² / σ1                        noise amplification index
O5     1 / Σ 1/σi                      harmonic mean divided by L
A      1 / Σ σi⁻²                      A-optimality: 1 / tr((JᵀJ)⁻¹)
=====  ==============================  ===========================================

All indices are "larger is better". O1 equals det(JᵀJ)^(1/(2L))/√m, so maximising
O1 for a fixed m is D-optimal design.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pincal.errors import PincalError, UnknownNameError
from pincal.sensitivity import RANK_RTOL, jacobian_rank, numerical_rank, numerical_ranks

__all__ = [
    "INDEX_NAMES",
    "ObservabilityIndices",
    "batch_indices",
    "indices_from_singular_values",
    "numerical_rank",
    "observability",
]

INDEX_NAMES: tuple[str, ...] = ("O1", "O2", "O3", "O4", "O5", "A")
"""Names accepted by :meth:`ObservabilityIndices.get` and the selection functions."""


def check_index_name(name: str) -> str:
    """``name`` if it is an observability index (O1–O5), else UnknownNameError."""
    if name not in INDEX_NAMES:
        raise UnknownNameError("observability index name", name, INDEX_NAMES)
    return name


def as_stacked(J: ArrayLike, what: str = "J") -> NDArray[np.float64]:
    """Return J as a finite 2-D float array (rows, n); (m, k, n) blocks are stacked."""
    arr = np.asarray(J, dtype=float)
    if arr.ndim == 3:
        arr = arr.reshape(-1, arr.shape[-1])
    if arr.ndim != 2 or arr.shape[1] == 0:
        raise PincalError(
            f"{what} must have shape (rows, n) or (m, k, n) with n >= 1; got {np.shape(J)}"
        )
    if not np.all(np.isfinite(arr)):
        raise PincalError(f"{what} contains NaN or infinite entries")
    return arr


def batch_indices(
    sigma: ArrayLike,
    m: int,
    names: Sequence[str] = INDEX_NAMES,
    rtol: float = RANK_RTOL,
    full: ArrayLike | None = None,
) -> dict[str, NDArray[np.float64]]:
    """The index formulas, once, for a batch of designs (every caller uses this).

    O1 = (σ1⋯σL)^(1/L)/√m, O2 = σL/σ1, O3 = σL, O4 = σL²/σ1, O5 = 1/Σ(1/σi),
    A = 1/Σσi⁻²; all are 0 for a design whose rank (σi > rtol·σ1,
    :func:`pincal.sensitivity._rank.numerical_rank`) is below L.

    Args:
        sigma: singular values (B, L), each row descending, one design per row; L is
            the number of parameters (pad with zeros when a design has fewer rows).
        m: number of poses of every design (enters O1 only), ≥ 1.
        names: the indices wanted, from :data:`INDEX_NAMES`.
        rtol: relative rank threshold.
        full: (B,) whether each design has full rank, decided by the caller (pose
            selection passes :func:`pincal.sensitivity.full_jacobian_ranks`, the rank
            rule of every command); None: the rule above on ``sigma``.

    Returns:
        ``{name: values (B,)}``.
    """
    s = np.asarray(sigma, dtype=float)
    if s.ndim != 2:
        raise PincalError(f"sigma must be a batch (B, L) of singular values; got {s.shape}")
    if m < 1:
        raise PincalError(f"number of poses m must be >= 1; got {m}")
    L = s.shape[1]
    if full is None:
        ok: NDArray[np.bool_] = (numerical_ranks(s, rtol) == L) & (L > 0)
    else:
        ok = np.asarray(full, dtype=bool) & (L > 0) & np.all(s > 0.0, axis=1)
    out = {check_index_name(name): np.zeros(s.shape[0]) for name in names}
    if not np.any(ok):
        return out
    sf = s[ok]
    s1, sL = sf[:, 0], sf[:, -1]
    formulas = {
        "O1": lambda: np.exp(np.mean(np.log(sf), axis=1)) / np.sqrt(m),
        "O2": lambda: sL / s1,
        "O3": lambda: sL,
        "O4": lambda: sL * sL / s1,
        "O5": lambda: 1.0 / np.sum(1.0 / sf, axis=1),
        "A": lambda: 1.0 / np.sum(sf**-2, axis=1),
    }
    for name, values in out.items():
        values[ok] = formulas[name]()
    return out


@dataclass(frozen=True, eq=False)
class ObservabilityIndices:
    """Observability indices of one stacked identification Jacobian.

    Attributes:
        O1: (σ1⋯σL)^(1/L)/√m (0 if rank-deficient).
        O2: σL/σ1 (0 if rank-deficient).
        O3: σL (0 if rank-deficient).
        O4: σL²/σ1 (0 if rank-deficient).
        O5: 1/Σ(1/σi) (0 if rank-deficient).
        a_optimality: 1/Σσi⁻² = 1/tr((JᵀJ)⁻¹) (0 if rank-deficient).
        singular_values: all L = n singular values, descending, shape (n,); when
            the Jacobian has fewer rows than columns the missing ones are 0.
        rank: numerical rank of J.
        m: number of poses used for O1.
    """

    O1: float
    O2: float
    O3: float
    O4: float
    O5: float
    a_optimality: float
    singular_values: NDArray[np.float64]
    rank: int
    m: int

    @property
    def full_rank(self) -> bool:
        """True when every parameter is observable (rank == n)."""
        return self.rank == self.singular_values.size

    @property
    def condition_number(self) -> float:
        """σ1/σL (inf if rank-deficient)."""
        return float("inf") if self.O2 == 0.0 else 1.0 / self.O2

    def get(self, name: str) -> float:
        """Index by name: one of "O1".."O5", "A"."""
        check_index_name(name)
        return self.a_optimality if name == "A" else float(getattr(self, name))

    def as_dict(self) -> dict[str, float]:
        """All indices by name."""
        return {name: self.get(name) for name in INDEX_NAMES}


def indices_from_singular_values(
    sigma: ArrayLike, m: int, rank: int | None = None
) -> ObservabilityIndices:
    """Observability indices from the singular values of a stacked Jacobian.

    Args:
        sigma: singular values, shape (n,), descending (zeros allowed).
        m: number of poses (enters O1 only).
        rank: numerical rank; default: the rank rule σi > 1e-8·σ1
            (:func:`pincal.sensitivity._rank.numerical_rank`).
    """
    s = np.sort(np.asarray(sigma, dtype=float).reshape(-1))[::-1]
    n = s.size
    if rank is None:
        rank = numerical_rank(s)
    if m < 1:
        raise PincalError(f"number of poses m must be >= 1; got {m}")
    if rank < n or n == 0:
        zero = 0.0
        return ObservabilityIndices(zero, zero, zero, zero, zero, zero, s, rank, m)
    v = {name: float(x[0]) for name, x in batch_indices(s[None, :], m, rtol=0.0).items()}
    return ObservabilityIndices(
        O1=v["O1"],
        O2=v["O2"],
        O3=v["O3"],
        O4=v["O4"],
        O5=v["O5"],
        a_optimality=v["A"],
        singular_values=s,
        rank=rank,
        m=m,
    )


def observability(J: ArrayLike, m: int | None = None) -> ObservabilityIndices:
    """Observability indices O1..O5 and A-optimality of an identification Jacobian.

    Args:
        J: scaled identification Jacobian, stacked (rows, n) or blocks (m, k, n).
        m: number of poses. Default: ``J.shape[0]`` for blocks; for a 2-D J every
            row counts as its own pose (m = rows), so pass m explicitly when a
            stacked Jacobian has several rows per pose.

    Returns:
        The indices. L = n: all n singular values count. If J is rank-deficient
        (rank < n, which includes rows < n), σL = 0 and every index that contains
        σL — O1 (product), O2, O3, O4, O5 and A (sums of 1/σi) — is reported as 0.
    """
    arr_in = np.asarray(J, dtype=float)
    if m is None:
        m = arr_in.shape[0] if arr_in.ndim >= 2 else 1
    arr = as_stacked(arr_in)
    n = arr.shape[1]
    s = np.linalg.svd(arr, compute_uv=False)
    if s.size < n:
        s = np.concatenate([s, np.zeros(n - s.size)])
    return indices_from_singular_values(s, int(m), jacobian_rank(arr))
