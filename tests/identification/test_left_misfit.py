"""Outliers explain a misfit only when the fit without them passes the χ² test (issue 25).

Under a 1 % bar scale the gate named two good readings of a ballbar file as outliers
(`scripts/studies/instrument_gate.py`, seed 6): every reading was off, those two most.
"""

from __future__ import annotations

import numpy as np

from pincal.identification._verdict import GateLimits
from pincal.identification.gate._fit_issues import left_misfit


def _linear(rng, m=60, p=20, scale=1.0, bad=()):
    A = rng.standard_normal((m, 1, p))
    z = scale * rng.standard_normal((m, 1))
    z[list(bad)] += 50.0
    M = A.reshape(m, p)  # residuals of the refit without the bad readings
    keep = np.setdiff1d(np.arange(m), bad)
    x = np.linalg.lstsq(M[keep], z.ravel()[keep], rcond=None)[0]
    return A, (z.ravel() - M @ x).reshape(m, 1)


def test_true_outliers_leave_no_misfit():
    """Without the bad readings the others fit their declared σ: the outliers explain it."""
    rng = np.random.default_rng(0)
    left = [left_misfit(*_linear(rng, bad=(3, 40)), (3, 40), GateLimits()) for _ in range(50)]
    assert left.count("") >= 49, left  # χ² test at p < 1e-3: ≤ 1 in 50 expected


def test_a_misfit_of_every_reading_is_not_blamed_on_the_largest():
    """Every reading 3× its declared σ: removing the two largest leaves χ²/ν ≈ 9."""
    rng = np.random.default_rng(1)
    A, z = _linear(rng, scale=3.0)
    worst = tuple(int(i) for i in np.argsort(-np.abs(z[:, 0]))[:2])
    text = left_misfit(A, z, worst, GateLimits())
    assert "the misfit is not a few bad poses" in text and "on 38 (p = " in text, text
