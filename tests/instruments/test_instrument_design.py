"""Pose design for instruments: candidates, exchange selection and the Cramér–Rao bound."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from pincal.design import select_poses
from pincal.errors import MeasurementError
from pincal.identification import (
    identify_instruments,
    instrument_blocks,
    instrument_candidates,
    instrument_cramer_rao,
)
from pincal.measure import Distance, Point, simulate_instrument
from pincal.sensitivity import analyse_jacobian


def _base(cands, n):
    J = cands.jacobians[:, 0, :]
    order = np.r_[np.arange(n, J.shape[1]), np.arange(n)]
    ident = analyse_jacobian(J[:, order], tuple(cands.param_names[i] for i in order))
    return np.sort(order[ident.base])


@pytest.fixture(scope="module")
def ballbar(stewart, stewart42):
    home = stewart.frame_placement(stewart.q_home).translation
    inst, theta = Distance(1e-6), np.r_[home - np.array([0, 0, 0.1]), 0.0]
    cands = instrument_candidates(stewart, stewart42, inst, theta, 150, rng=0, max_tilt=0.1)
    return inst, theta, cands


def test_ballbar_candidates_lie_on_the_bar_sphere(stewart, stewart42, ballbar):
    inst, theta, cands = ballbar
    assert len(cands) > 100 and cands.components == ("v",)
    assert cands.jacobians.shape == (len(cands), 1, len(stewart42) + 4)
    r = np.linalg.norm(cands.positions - theta[:3], axis=1)
    np.testing.assert_allclose(r, 0.1, atol=1e-9)
    J, _, _ = instrument_blocks(stewart, stewart42, inst, theta, cands.q_act[:5])
    np.testing.assert_allclose(J, cands.jacobians[:5], atol=1e-12)
    with pytest.raises(MeasurementError, match="has none"):
        instrument_candidates(stewart, stewart42, Point(), np.zeros(1))


def test_exchange_selection_beats_random_on_the_bound(stewart, stewart42, ballbar):
    inst, _, cands = ballbar
    base = _base(cands, len(stewart42))
    assert base.size == 37
    sub = dataclasses.replace(
        cands,
        jacobians=cands.jacobians[:, :, base],
        param_names=tuple(cands.param_names[i] for i in base),
    )
    design = select_poses(sub, 45, "O1", rng=0)
    chosen = instrument_cramer_rao(cands.jacobians[design.indices], inst.std, base)
    rand = np.random.default_rng(3).choice(len(cands), 45, replace=False)
    random_bound = instrument_cramer_rao(cands.jacobians[rand], inst.std, base)
    assert np.sqrt(np.diag(chosen)).max() < np.sqrt(np.diag(random_bound)).max()


@pytest.mark.slow
def test_monte_carlo_fit_attains_the_bound(stewart, stewart42, ballbar):
    """Mean Mahalanobis distance of the fitted set ≈ 1 (within 4 standard errors)."""
    inst, theta, cands = ballbar
    n = len(stewart42)
    base = _base(cands, n)
    sub = dataclasses.replace(
        cands,
        jacobians=cands.jacobians[:, :, base],
        param_names=tuple(cands.param_names[i] for i in base),
    )
    rows = cands.q_act[select_poses(sub, 60, "O1", rng=0).indices]
    truth = np.zeros(n)
    truth[base[base < n]] = np.random.default_rng(1).uniform(-2e-4, 2e-4, (base < n).sum())
    actual = stewart42.apply(stewart, truth)
    cov = instrument_cramer_rao(
        instrument_blocks(actual, stewart42, inst, theta, rows)[0], inst.std, base
    )
    d2 = []
    for r in range(15):
        data = simulate_instrument(actual, inst, theta, rows, np.random.default_rng(50 + r))
        fit = identify_instruments(stewart, stewart42, [data])
        assert np.array_equal(fit.fitted, base)
        delta = (fit.values - np.r_[truth, theta])[base]
        d2.append(delta @ np.linalg.solve(cov, delta) / base.size)
    mean, se = np.mean(d2), np.std(d2, ddof=1) / np.sqrt(len(d2))
    assert abs(mean - 1.0) < 4 * se + 0.1, (mean, se)
