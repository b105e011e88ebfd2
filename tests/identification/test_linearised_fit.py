"""The linearised leave-fold-out that ranks a prior's candidates (no refits).

For a linear model the one-step leave-fold-out of :class:`LinearisedFit` is the refit
without the fold, exactly; on a simulated UR5 seen by a marker its K-fold held-out
errors follow those of real refits (:func:`pincal.validation.cross_validate`).
"""

from __future__ import annotations

import numpy as np
import pytest

from pincal.identification import LinearisedFit, Prior, fit_markers, linearise_marker_fit
from pincal.validation import cross_validate, kfold, linearised_cross_validation
from tests.identification.test_marker_fit import _ur5_case


def test_leave_out_is_the_refit_of_a_linear_model():
    rng = np.random.default_rng(3)
    m, k, f = 12, 3, 5  # poses, rows per pose, unknowns
    A = rng.normal(size=(m * k, f))
    y = rng.normal(size=m * k)
    sigma = rng.uniform(0.5, 2.0, m * k)
    w = rng.uniform(0.3, 1.0, m * k)  # robust weights
    prec = np.array([0.0, 0.0, 4.0, 1.0, 0.25])  # a prior on three unknowns

    def refit(keep: np.ndarray) -> np.ndarray:  # minimises Σ w ((y − A x)/σ)² + Σ prec x²
        a = np.sqrt(w[keep])[:, None] * A[keep] / sigma[keep, None]
        b = np.sqrt(w[keep]) * y[keep] / sigma[keep]
        rows = np.vstack([a, np.diag(np.sqrt(prec))])
        return np.linalg.lstsq(rows, np.concatenate([b, np.zeros(f)]), rcond=None)[0]

    x = refit(np.ones(m * k, dtype=bool))
    pose = np.repeat(np.arange(m), k)
    fit = LinearisedFit(
        residuals=(y - A @ x) / sigma,
        jacobian=-A / sigma[:, None],
        sigma=sigma,
        weights=w,
        precision=prec,
        pose=pose,
        marker=np.zeros(m * k, dtype=int),
        component=np.tile(np.arange(k), m),
    )
    out = np.array([2, 7, 8])
    x_out = refit(~np.isin(pose, out))
    assert np.allclose(fit.without(out), y - A @ x_out, atol=1e-12)
    assert not np.allclose(fit.without(out), y - A @ x, atol=1e-3)  # the fold moved the fit


def test_linearised_cv_ranks_priors_as_the_refits_do_on_a_simulated_arm():
    """Errors of 1 mm / 1 mrad, noise 0.05 mm: where the data dominate (σ 10 mm) the
    leave-fold-out is the refits' to 1 %; a prior that pulls the fit far from the data
    (σ 0.1 mm) is first order only (each fold's refit re-estimates the noise, which
    scales the prior's pull), but the candidates rank as the refits rank them."""
    mech, setup, meas = _ur5_case(30, None, 5)
    folds = kfold(len(meas), 5, 0)
    approx, exact = [], []
    for s in (1e-4, 1e-3, 1e-2):
        prior = Prior(s, s)
        fit = fit_markers(mech, setup, meas, prior=prior)
        approx.append(linearised_cross_validation(linearise_marker_fit(fit, setup, meas), folds))
        refit = lambda d, p=prior: fit_markers(mech, setup, d, prior=p).calibrated  # noqa: E731
        exact.append(cross_validate(refit, meas, 5, 0))
    assert [f.tolist() for f in approx[0].folds] == [f.tolist() for f in exact[0].folds]
    assert (
        np.argsort([a.rms for a in approx]).tolist() == np.argsort([e.rms for e in exact]).tolist()
    )
    weak, refits = approx[-1], exact[-1]
    assert weak.rms == pytest.approx(refits.rms, rel=0.01)
    assert weak.fit_rms == pytest.approx(refits.fit_rms, rel=0.01)
    assert np.corrcoef(weak.held_out, refits.held_out)[0, 1] > 0.99  # pose by pose
    assert weak.rms > 1.5 * fit.result.after.rms_position  # held out: worse than the fit
