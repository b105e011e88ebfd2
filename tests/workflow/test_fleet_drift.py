"""Drift between two calibrations of a unit: T² = dᵀ(C₁ + C₂)⁺d against χ²(rank)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from pincal.workflow import UnitEstimate, session_drift


def _covariance(rng: np.random.Generator, p: int, rank: int) -> np.ndarray:
    A = rng.standard_normal((p, rank)) * np.logspace(-5, -3, rank)  # metres, mixed scales
    return A @ A.T


def _pairs(rng, n, p, rank, drift=None):
    """n units measured twice around their own truths, C₁ ≠ C₂ (other poses)."""
    names = tuple(f"j{k}.tx" for k in range(p))
    out = []
    for i in range(n):
        truth = rng.standard_normal(p) * 1e-3
        for date in ("2026-01-15", "2026-07-15"):
            C = _covariance(rng, p, rank)
            w, V = np.linalg.eigh(C)
            x = truth + V @ (np.sqrt(np.clip(w, 0, None)) * rng.standard_normal(p))
            if drift is not None and i == 0 and date == "2026-07-15":
                x = x + drift
            out.append((f"SN-{i:04d}", date, UnitEstimate(f"SN-{i:04d}@{date}", names, x, C)))
    return out


def test_without_drift_the_statistic_is_chi2_of_the_rank():
    rng = np.random.default_rng(0)
    # full rank, and C₁ + C₂ singular (each session resolves 5 of 8 directions, the
    # same 5 in both: a parameter combination no session identifies)
    for p, rank in ((6, 6), (8, 5)):
        names = tuple(f"j{k}.tx" for k in range(p))
        A = rng.standard_normal((p, rank)) * 1e-4
        sessions = []
        for i in range(400):
            for date in ("a", "b"):
                B = A @ np.diag(rng.uniform(0.5, 2.0, rank))
                x = B @ rng.standard_normal(rank)
                sessions.append((f"U{i}", date, UnitEstimate(f"U{i}@{date}", names, x, B @ B.T)))
        found = session_drift(sessions, 0.01)
        assert len(found) == 400 and {d.dof for d in found} == {rank}
        T2 = np.array([d.distance for d in found])
        # mean of χ²(r) is r, its standard error √(2r / 400)
        assert abs(T2.mean() - rank) < 4 * np.sqrt(2 * rank / 400)
        assert stats.kstest(T2, stats.chi2(rank).cdf).pvalue > 1e-3
        assert sum(d.drifted for d in found) <= 2  # fleet-wise α = 1 %: 0 expected


def test_a_moved_part_is_named_and_the_others_are_not():
    rng = np.random.default_rng(1)
    drift = np.zeros(6)
    drift[2] = 5e-3  # 5 mm on one parameter
    found = session_drift(_pairs(rng, 20, 6, 6, drift), 0.01)
    drifted = [d.id for d in found if d.drifted]
    assert drifted == ["SN-0000"]
    first = found[0]
    assert (first.before, first.after) == ("2026-01-15", "2026-07-15")
    name, z, change = first.largest[0]
    assert name == "j2.tx" and change == pytest.approx(5e-3, abs=1e-3) and z > 3


def test_sessions_are_ordered_by_date_and_single_sessions_not_compared():
    rng = np.random.default_rng(2)
    pairs = _pairs(rng, 2, 3, 3)
    three = [*pairs, ("SN-0000", "2026-03-01", pairs[0][2])]
    found = session_drift([three[1], three[4], three[0], three[2]], 0.01)
    assert [(d.id, d.before, d.after) for d in found] == [
        ("SN-0000", "2026-01-15", "2026-03-01"),
        ("SN-0000", "2026-03-01", "2026-07-15"),
    ]
    assert found[0].distance == pytest.approx(0.0, abs=1e-9)  # the same estimate twice
