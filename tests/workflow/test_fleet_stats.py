"""The out-of-family test on synthetic estimates drawn from its own model."""

from __future__ import annotations

import numpy as np
import pytest

from pincal.errors import ParameterError
from pincal.workflow import UnitEstimate, fleet_statistics


def _fleet(seed, M, p, planted, shift):
    rng = np.random.default_rng(seed)
    tau = rng.uniform(0.5, 1.5, p)
    units, bad = [], set(rng.choice(M, planted, replace=False).tolist())
    for u in range(M):
        A = rng.standard_normal((p, p)) * 0.5 / np.sqrt(p)
        C = A @ A.T + 0.05 * np.eye(p)
        x = tau * rng.standard_normal(p) + rng.multivariate_normal(np.zeros(p), C)
        if u in bad:
            x[:3] += shift * tau[:3] * rng.choice([-1, 1], 3)
        units.append(UnitEstimate(f"u{u}", tuple(f"k{j}" for j in range(p)), x, C))
    return units, {f"u{u}" for u in bad}


def test_planted_units_are_flagged_and_the_family_is_not():
    units, bad = _fleet(0, 40, 6, 2, 10.0)
    st = fleet_statistics(units, alpha=0.01)
    flagged = {v.id for v in st.units if v.out_of_family}
    assert bad <= flagged and len(flagged - bad) <= 1
    assert st.threshold > 6  # χ²(6) at 0.01/40


def test_refusals():
    units, _ = _fleet(1, 5, 3, 0, 0.0)
    with pytest.raises(ParameterError, match="at least 3"):
        fleet_statistics(units[:2])
    with pytest.raises(ParameterError, match="alpha"):
        fleet_statistics(units, alpha=1.5)


@pytest.mark.slow
def test_detection_and_false_alarms_over_seeds():
    """200 units, 42 parameters, 6 planted at 8 τ on 3 parameters, 5 seeds."""
    found = false = 0
    for seed in range(5):
        units, bad = _fleet(seed, 200, 42, 6, 8.0)
        flagged = {v.id for v in fleet_statistics(units).units if v.out_of_family}
        found += len(flagged & bad)
        false += len(flagged - bad)
    assert found >= 0.95 * 30 and false <= 5


@pytest.mark.slow
def test_small_fault_free_fleets_are_rarely_flagged():
    """Fleets of 6 units of the test's own model, none faulty: with its limit at alpha/M
    alone more than half of such fleets flagged a unit (τ fitted to the units it
    judges); calibrated by fault-free fleets of the fitted family, at most 2 of 20
    (alpha 1 %: 0.2 expected; 2 or more has chance 1.7 %)."""
    flagged = sum(
        any(v.out_of_family for v in fleet_statistics(_fleet(seed, 6, 5, 0, 0.0)[0]).units)
        for seed in range(20)
    )
    assert flagged <= 2


def test_a_single_error_of_the_detectable_size_is_flagged_95_percent_of_the_time():
    """Every unit with one covariance: the stated size is exact, checked by Monte Carlo."""
    rng = np.random.default_rng(4)
    p = 5
    A = rng.standard_normal((p, p))
    C = A @ A.T / p + 0.05 * np.eye(p)  # correlated estimation errors
    tau = rng.uniform(0.5, 1.5, p)
    units = [
        UnitEstimate(f"u{u}", tuple(f"k{j}" for j in range(p)),
                     tau * rng.standard_normal(p) + rng.multivariate_normal(np.zeros(p), C), C)
        for u in range(60)
    ]  # fmt: skip
    st = fleet_statistics(units)
    S = C + np.diag(st.production_std**2)
    draws = 4000
    for j in range(p):
        shift = np.zeros(p)
        shift[j] = st.detectable[j]
        r = shift + rng.multivariate_normal(np.zeros(p), S, size=draws)
        rate = np.mean(np.einsum("ui,ui->u", r, np.linalg.solve(S, r.T).T) > st.threshold)
        assert rate == pytest.approx(0.95, abs=4 * np.sqrt(0.95 * 0.05 / draws)), j
