"""Orthogonal arrays for measurement-pose candidates (seed 001).

Bose's strength-2 construction L_{p²}(p^{p+1}) over a prime number of levels, the
smallest such array for a number of levels and factors, and the mapping of its
levels onto workspace factor ranges.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pincal.errors import PincalError

__all__ = ["bose_array", "map_to_ranges", "orthogonal_array"]


def is_prime(p: int) -> bool:
    """True when p is a prime number."""
    if p < 2:
        return False
    return all(p % d for d in range(2, int(p**0.5) + 1))


def bose_array(p: int) -> NDArray[np.int_]:
    """Bose's strength-2 orthogonal array L_{p²}(p^{p+1}) over GF(p).

    Run r = (i, j) ∈ GF(p)² (r = i·p + j) gets the levels
    (i, j, j + i, j + 2i, …, j + (p−1)i) mod p. Any two columns form every
    level pair exactly once: column i with column j + s·i fixes (i, j), and two
    columns j + s·i, j + t·i (s ≠ t) fix i = (a − b)/(s − t) because p is prime.

    Args:
        p: prime number of levels.

    Returns:
        Array (p², p + 1) of levels 0..p−1.
    """
    if not isinstance(p, (int, np.integer)) or not is_prime(int(p)):
        raise PincalError(f"Bose construction needs a prime number of levels; got {p!r}")
    p = int(p)
    i = np.repeat(np.arange(p), p)
    j = np.tile(np.arange(p), p)
    cols = [i] + [(j + s * i) % p for s in range(p)]
    return np.stack(cols, axis=1)


def orthogonal_array(levels: int, factors: int) -> NDArray[np.int_]:
    """Smallest Bose array with at least ``levels`` levels and ``factors`` columns.

    Picks the smallest prime p ≥ levels with p + 1 ≥ factors and returns the
    first ``factors`` columns of L_{p²}(p^{p+1}) (a column subset of an
    orthogonal array is one). Examples: (5, 6) → L25(5⁶), (7, 8) → L49(7⁸),
    (3, 6) → p = 5.

    Args:
        levels: minimum number of levels per factor, ≥ 2.
        factors: number of factors (columns), ≥ 1.

    Returns:
        Array (p², factors) of levels 0..p−1; p = ``table.max() + 1``.
    """
    if levels < 2 or factors < 1:
        raise PincalError(
            f"need levels >= 2 and factors >= 1; got levels={levels}, factors={factors}"
        )
    p = max(int(levels), int(factors) - 1, 2)
    while not is_prime(p):
        p += 1
    return bose_array(p)[:, :factors]


def map_to_ranges(table: ArrayLike, lower: ArrayLike, upper: ArrayLike) -> NDArray[np.float64]:
    """Map an orthogonal array onto workspace factor ranges.

    Level l of a p-level column becomes lower + (upper − lower)·l/(p − 1): the p
    levels are evenly spaced and include both ends of each range.

    Args:
        table: integer array (runs, factors) with levels 0..p−1.
        lower: lower bound of each factor, shape (factors,) [m or rad].
        upper: upper bound of each factor, shape (factors,).

    Returns:
        Factor values (runs, factors), e.g. workspace poses (x, y, z, rx, ry, rz).
    """
    t = np.asarray(table)
    lo = np.asarray(lower, dtype=float).reshape(-1)
    hi = np.asarray(upper, dtype=float).reshape(-1)
    if t.ndim != 2 or not np.issubdtype(t.dtype, np.integer) or t.min(initial=0) < 0:
        raise PincalError(
            f"table must be a non-negative integer array (runs, factors); got {t.shape}"
        )
    if lo.shape != (t.shape[1],) or hi.shape != (t.shape[1],):
        raise PincalError(
            f"lower and upper need one bound per factor ({t.shape[1]}); got {lo.shape}, {hi.shape}"
        )
    p = int(t.max()) + 1
    if p < 2:
        raise PincalError("table must have at least two levels")
    return lo + (hi - lo) * (t / (p - 1))
