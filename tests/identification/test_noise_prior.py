"""With a prior and the noise estimated, the fit weighs data and prior by the σ it leaves.

The prior's weight against the data depends on σ itself, not only on the ratio of the
blocks' σ: the fit must be the one the estimated σ, declared, would give — not the one
weighted by the start residuals (which for a far start are model errors, not noise).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import pincal
from pincal.identification import GaussNewtonOptions, identify
from pincal.model import sample_actuators


@pytest.fixture(scope="module")
def case(stewart, stewart42):
    rng = np.random.default_rng(5)
    actual = stewart42.apply(stewart, rng.normal(0.0, 1e-3, len(stewart42)))
    noise = pincal.NoiseModel(0.01, 0.02)  # mm, mrad
    meas = pincal.simulate_measurements(actual, sample_actuators(stewart, 25, rng), noise, rng)
    return dataclasses.replace(meas, noise=None)  # the noise is to be estimated


@pytest.mark.parametrize("sigma", [3e-4, 3e-3])
def test_estimated_noise_with_a_prior_is_its_own_fixed_point(stewart, stewart42, case, sigma):
    n = len(stewart42)
    opts = GaussNewtonOptions(prior_std=(sigma,) * n, prior_mean=(0.0,) * n)
    est = identify(stewart, stewart42, case, options=opts)
    w = est.weighting
    assert w is not None and w.source.startswith("estimate") and w.converged
    # the start residuals (errors of ~1 mm) are far above the noise (10 µm)
    assert est.before.rms_position > 20 * w.position_std
    declared = {"position": w.position_std * 1e3, "orientation": w.orientation_std * 1e3}
    fixed = identify(stewart, stewart42, case, options=opts, noise=declared)
    # the same fit to the settling tolerance (0.1 % of σ) — in units of its σ
    assert np.all(est.identified == fixed.identified)
    moved = (est.values - fixed.values) / fixed.std
    assert np.max(np.abs(moved)) < 0.05


@pytest.mark.slow  # 80 fits, ~8 s
def test_noise_and_covariance_with_a_prior_count_what_the_prior_holds(stewart, stewart42):
    """With the truth drawn from the prior (10 poses, 40 draws): E[σ̂²] = σ², the
    reduced χ² at the declared σ is 1 and the covariance covers the error (d²/k = 1).

    The redundancy is that of the regularised fit, N − tr(H) with
    H = J (JᵀJ + diag(1/σ_prior)²)⁻¹ Jᵀ: counted as N − 42 (every parameter fitted by
    the data), σ̂² came out 2.3× (position) and 3.6× (orientation) too large and the
    reduced χ² of a right model 2.2.
    """
    n, sp = len(stewart42), 3e-5  # prior σ: 0.03 mm / 0.03 mrad, the truth's spread
    opts = GaussNewtonOptions(prior_std=(sp,) * n, prior_mean=(0.0,) * n)
    noise = pincal.NoiseModel(0.01, 0.02)  # mm, mrad
    rows = []
    for seed in range(40):
        rng = np.random.default_rng(100 + seed)
        truth = rng.normal(0.0, sp, n)
        actual = stewart42.apply(stewart, truth)
        meas = pincal.simulate_measurements(actual, sample_actuators(stewart, 10, rng), noise, rng)
        est = identify(stewart, stewart42, dataclasses.replace(meas, noise=None), options=opts)
        decl = identify(stewart, stewart42, meas, options=opts)
        w = est.weighting
        assert w is not None and decl.identified.all()
        e = decl.full_values - truth
        d2 = float(e @ np.linalg.solve(decl.covariance, e)) / n
        rows.append([(w.position_std / 1e-5) ** 2, (w.orientation_std / 2e-5) ** 2,
                     decl.reduced_chi2, d2])  # fmt: skip
    a = np.asarray(rows)
    mean, se = a.mean(axis=0), a.std(axis=0, ddof=1) / np.sqrt(len(a))
    # measured: σ̂²/σ² 0.94, 0.95 ± 0.05; χ²/ν 0.95 ± 0.04; d²/k 0.97 ± 0.03
    assert np.all(np.abs(mean - 1.0) < 3.0 * se + 0.05), (mean, se)
