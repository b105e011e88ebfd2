"""Efficiency against the Cramér–Rao bound when parameters mix lengths and angles."""

from __future__ import annotations

import numpy as np
import pytest

from pincal.design import efficiency
from pincal.errors import PincalError

UNITS = ("m", "m", "rad", "rad", "m")


def _mixed_bound(rng: np.random.Generator) -> np.ndarray:
    """A correlated bound whose length entries are ~1e-5 m and angle entries ~1e-2 rad."""
    s = np.diag([1e-5, 2e-5, 1e-2, 3e-2, 5e-6])
    A = rng.standard_normal((5, 5))
    corr = A @ A.T + 5 * np.eye(5)
    d = np.sqrt(np.diag(corr))
    return s @ (corr / np.outer(d, d)) @ s


def test_draws_from_a_mixed_unit_bound_are_efficient_in_every_form():
    rng = np.random.default_rng(3)
    C = _mixed_bound(rng)
    e = rng.multivariate_normal(np.zeros(5), C, size=4000)
    eff = efficiency(e, C, UNITS)
    assert abs(eff.whitened - 1.0) < 4 * eff.whitened_se and eff.whitened_se < 0.05
    assert set(eff.by_unit) == {"m", "rad"}
    for eta, se in eff.by_unit.values():
        assert abs(eta - 1.0) < 4 * se and se < 0.05
    # the trace form would add m² and rad²: it is not reported for mixed units
    assert np.isnan(eff.efficiency) and np.isnan(eff.efficiency_se)
    assert eff.units == UNITS


def test_a_wasted_length_parameter_shows_in_whitened_and_length_efficiency():
    """Trace form over mixed units hides a 10× worse length estimate; whitened does not."""
    rng = np.random.default_rng(4)
    C = _mixed_bound(rng)
    e = rng.multivariate_normal(np.zeros(5), C, size=4000)
    bad = e.copy()
    bad[:, 0] *= 10.0  # the first length parameter is estimated 10× worse than its bound
    eff = efficiency(bad, C, UNITS)
    mixed_trace = np.trace(C) / np.mean(np.sum(bad**2, axis=1))
    assert mixed_trace > 0.95  # dominated by the rad² entries: looks efficient
    assert eff.by_unit["m"][0] < 0.2  # the length class reveals it
    assert eff.by_unit["rad"][0] == pytest.approx(efficiency(e, C, UNITS).by_unit["rad"][0])
    assert eff.whitened < 0.5  # unit-free form reveals it too


def test_whitened_efficiency_is_unit_free():
    """Expressing the angles in mrad instead of rad changes nothing in the whitened form."""
    rng = np.random.default_rng(5)
    C = _mixed_bound(rng)
    e = rng.multivariate_normal(np.zeros(5), 1.3 * C, size=500)
    scale = np.array([1.0, 1.0, 1e3, 1e3, 1.0])
    a = efficiency(e, C, UNITS)
    b = efficiency(e * scale, C * np.outer(scale, scale), UNITS)
    assert b.whitened == pytest.approx(a.whitened, rel=1e-9)
    assert b.whitened_se == pytest.approx(a.whitened_se, rel=1e-9)
    assert b.by_unit["m"][0] == pytest.approx(a.by_unit["m"][0], rel=1e-12)


def test_single_unit_trace_form_unchanged_and_rank_deficient_bound():
    rng = np.random.default_rng(6)
    A = rng.standard_normal((4, 2))
    C = A @ A.T  # rank 2: errors live in the range of C
    e = rng.multivariate_normal(np.zeros(4), C, size=3000)
    eff = efficiency(e, C)
    assert eff.units == ("m",) * 4
    assert eff.efficiency == pytest.approx(np.trace(C) / np.mean(np.sum(e**2, axis=1)))
    assert eff.by_unit["m"][0] == pytest.approx(eff.efficiency)
    # whitened on the range of C: E‖z‖² = rank = 2, so η_w ≈ 1 (not 2/4)
    assert abs(eff.whitened - 1.0) < 4 * eff.whitened_se


def test_units_must_match_the_parameters():
    C = np.eye(3)
    with pytest.raises(PincalError, match="units"):
        efficiency(np.zeros((4, 3)) + 1e-3, C, ("m", "rad"))
