"""The χ², F and t formulas from scipy.special equal scipy.stats' distributions."""

from __future__ import annotations

import pytest
from scipy import stats

from pincal.identification._distributions import chi2_isf, chi2_sf, f_isf, f_sf, norm_ppf, t_ppf


@pytest.mark.parametrize("nu", [1, 3, 40, 2000])
@pytest.mark.parametrize("x", [0.1, 1.0, 7.5, 80.0])
def test_chi2_tail_equals_scipy_stats(x: float, nu: int) -> None:
    assert chi2_sf(x, nu) == pytest.approx(stats.chi2.sf(x, nu), rel=1e-12, abs=1e-300)


@pytest.mark.parametrize(("d1", "d2"), [(1, 5), (6, 30), (12, 400)])
@pytest.mark.parametrize("q", [0.5, 0.05, 1e-4, 1e-12])
def test_f_tail_and_quantile_equal_scipy_stats(q: float, d1: int, d2: int) -> None:
    x = f_isf(q, d1, d2)
    assert f_sf(x, d1, d2) == pytest.approx(q, rel=1e-9)
    assert f_sf(x, d1, d2) == pytest.approx(stats.f.sf(x, d1, d2), rel=1e-9)
    if q >= 1e-4:
        assert x == pytest.approx(stats.f.isf(q, d1, d2), rel=1e-9)
    else:  # scipy.stats' own quantile is off by 2e-5 of q there; the beta inverse is not
        assert abs(stats.f.sf(x, d1, d2) - q) < abs(stats.f.sf(stats.f.isf(q, d1, d2), d1, d2) - q)


@pytest.mark.parametrize("nu", [1, 4, 25, 1e4])
@pytest.mark.parametrize("p", [0.5, 0.975, 0.999])
def test_t_quantile_equals_scipy_stats(p: float, nu: float) -> None:
    assert t_ppf(p, nu) == pytest.approx(stats.t.ppf(p, nu), rel=1e-10, abs=1e-14)


@pytest.mark.parametrize("nu", [1, 7, 300])
@pytest.mark.parametrize("q", [0.5, 0.05, 1e-6])
def test_chi2_and_normal_quantiles_equal_scipy_stats(q: float, nu: int) -> None:
    assert chi2_isf(q, nu) == pytest.approx(stats.chi2.isf(q, nu), rel=1e-10)
    assert norm_ppf(1 - q) == pytest.approx(stats.norm.ppf(1 - q), rel=1e-10, abs=1e-14)
