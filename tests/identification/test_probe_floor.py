"""The probes' detection floor, and serial correlation named apart from a drift."""

from __future__ import annotations

import numpy as np
import pytest

from pincal.identification._distributions import f_isf
from pincal.identification.gate._autocorrelation import serial_correlation
from pincal.identification.gate._misspecification import probe_misspecification
from pincal.identification.gate._probe_floor import POWER, floor_lambda


def _design(m: int, k: int, p: int, seed: int):
    rng = np.random.default_rng(seed)
    return rng.normal(size=(m * k, p)), rng


def test_floor_lambda_gives_the_power_by_simulation():
    """Draws of F(q, ν − q, λ) at the floor's λ exceed F_crit with the stated power."""
    q, dof, alpha = 3, 200, 1e-3 / 8
    lam = floor_lambda(q, dof, alpha, 0.0, 203.0)  # the F-test alone
    rng = np.random.default_rng(0)
    n = 20000
    num = rng.noncentral_chisquare(q, lam, n) / q
    den = rng.chisquare(dof, n) / dof
    hit = float(np.mean(num / den > f_isf(alpha, q, dof)))
    assert hit == pytest.approx(POWER, abs=3 * np.sqrt(POWER * (1 - POWER) / n))
    # the explained share needs more on a redundant design: a larger λ
    assert floor_lambda(q, dof, alpha, 0.25, 203.0) > 2 * lam


def _scale_hits(size: float, draws: int, seed: int) -> tuple[float, float]:
    """Share of draws whose scale probe fires with an error ``size`` × its column."""
    m, k, p = 60, 3, 8
    A, rng = _design(m, k, p, seed)
    col = rng.normal(size=(m, k, 1))
    sigma = np.ones((m, k))
    fired, floor = 0, np.nan
    for _ in range(draws):
        z = rng.normal(size=m * k) + size * col.ravel()
        (pr,) = probe_misspecification(A, z, {"scale": col}, sigma, ("x", "y", "z"), 1e-3)
        fired += pr.p_value < 1e-3 and pr.explained >= 0.25
        floor = pr.floor
    return fired / draws, floor


def test_errors_above_the_floor_are_caught_and_below_pass():
    _, floor = _scale_hits(0.0, 1, seed=4)
    assert np.isfinite(floor) and floor > 0
    above, _ = _scale_hits(1.2 * floor, 200, seed=4)
    below, _ = _scale_hits(0.5 * floor, 200, seed=4)
    assert above >= 0.9
    assert below <= 0.2


def test_ar1_residuals_are_correlated_after_a_drift_is_fitted():
    m, k = 80, 3
    A, rng = _design(m, k, 5, seed=2)
    A = A.reshape(m, k, 5)
    t = np.linspace(-0.5, 0.5, m)
    drift = np.zeros((m, k, k))
    for j in range(k):
        drift[:, j, j] = t
    e = np.zeros((m, k))
    for i in range(1, m):  # AR(1), ρ = 0.7
        e[i] = 0.7 * e[i - 1] + rng.normal(size=k)
    ar = serial_correlation(A, e, drift)
    assert ar is not None and ar.p_value < 1e-6 and ar.durbin_watson < 1.2
    linear = 5.0 * t[:, None] + rng.normal(size=(m, k))  # a drift and white noise
    assert serial_correlation(A, linear, None).p_value < 1e-6  # seen before the fit
    after = serial_correlation(A, linear, drift)
    assert after is not None and after.p_value > 1e-3


def test_floors_are_said_in_their_unit_and_beyond_the_workspace_as_not_detectable():
    """9.6 mm was printed "9.6e+03 µm"; a floor past the positions' spread (a trend the
    model nearly absorbs) or a gain of 100 % or more is not detectable with these poses."""
    from pincal.identification.gate._misspecification import Probe

    def text(name: str, floor: float, workspace: float = 0.28) -> str:
        return Probe(name, 1, 1.0, 0.5, 0.1, "", floor, workspace).floor_text()

    assert text("drift", 0.00958) == "a drift below 9.6 mm over the pose order"
    assert text("drift", 3.4e-5) == "a drift below 34 µm over the pose order"
    assert text("trend:tool x", 2.1e-4) == "a trend below 210 µm along the tool x"
    far = text("trend:actuator torso", 0.309)
    assert far.startswith("a trend along the actuator torso (not detectable with these poses")
    assert "310 mm" in far and "280 mm" in far
    assert text("gains", 0.33) == "an actuator gain error below 33 %"
    assert "not detectable" in text("gains", 1.5) and "150 %" in text("gains", 1.5)
    assert text("scale", 4.4e-5) == "a scale error below 0.0044 %"
    assert "not detectable" not in text("drift", 5.0, float("nan"))  # spread unknown
