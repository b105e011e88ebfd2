"""Tail probabilities and quantiles of the χ², F and Student-t distributions.

From :mod:`scipy.special` (the functions behind ``scipy.stats``), imported on first use
(the command line imports no scipy until it computes): importing ``scipy.stats`` costs
about a second of CPU, more than a whole calibration of a small data set, for four
formulas.
"""

from __future__ import annotations

__all__ = ["chi2_isf", "chi2_sf", "f_isf", "f_sf", "norm_ppf", "t_ppf"]


def chi2_sf(x: float, nu: float) -> float:
    """P(X > x) for X ~ χ²(ν)."""
    from scipy import special

    return float(special.chdtrc(nu, x))


def f_sf(x: float, d1: float, d2: float) -> float:
    """P(X > x) for X ~ F(d1, d2)."""
    from scipy import special

    return float(special.fdtrc(d1, d2, x))


def f_isf(q: float, d1: float, d2: float) -> float:
    """The x with P(X > x) = q for X ~ F(d1, d2), accurate for tiny q.

    P(X > x) = I_w(d2/2, d1/2) with w = d2 / (d2 + d1 x) (regularised incomplete beta),
    so x = d2 (1 − w) / (d1 w) with w the inverse of I at q.
    """
    from scipy import special

    w = float(special.betaincinv(d2 / 2.0, d1 / 2.0, q))
    return d2 * (1.0 - w) / (d1 * w)


def t_ppf(p: float, nu: float) -> float:
    """The x with P(T ≤ x) = p for T ~ Student-t(ν)."""
    from scipy import special

    return float(special.stdtrit(nu, p))


def chi2_isf(q: float, nu: float) -> float:
    """The x with P(X > x) = q for X ~ χ²(ν)."""
    from scipy import special

    return float(special.chdtri(nu, q))


def norm_ppf(p: float) -> float:
    """The x with P(Z ≤ x) = p for Z ~ N(0, 1)."""
    from scipy import special

    return float(special.ndtri(p))
