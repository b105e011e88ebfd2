"""One bound for a parameter the poses do not place (issue 36): the fit's hold and
`validate`'s withheld prediction (both 1σ beyond 20 mm / 0.1 rad) read
:data:`pincal.sensitivity.PLACEMENT_BOUND` and one rule, so the prediction is withheld
exactly where the fit holds."""

from __future__ import annotations

import numpy as np
import pytest

from pincal.identification.problem._fit_set import WeakBound
from pincal.sensitivity import PLACEMENT_BOUND, beyond_placement
from pincal.validation import prediction_caveat

NAMES, UNITS = ("a.tx", "a.rx", "b.ty"), ("m", "rad", "m")


def _whitened(std: np.ndarray) -> np.ndarray:
    """A whitened Jacobian (N, 3) whose parameters have the 1σ ``std`` and no correlation."""
    q, _ = np.linalg.qr(np.random.default_rng(0).normal(size=(40, 3)))
    return q / std  # orthogonal columns: (JᵀJ)⁻¹ = diag(std²)


@pytest.mark.parametrize("factor", [0.45, 0.499, 0.501, 0.9, 0.999, 1.001, 1.1])
def test_fit_and_validate_read_one_bound(factor):
    length, angle = PLACEMENT_BOUND
    std = np.array([factor * length, factor * angle, 1e-5])  # b.ty well placed
    Jw = _whitened(std)
    held = WeakBound(length, angle).held(Jw, np.arange(3), UNITS, 3)
    cov = np.linalg.inv(Jw.T @ Jw)
    caveat = prediction_caveat(NAMES, UNITS, cov)
    assert set(held) == ({0, 1} if factor > 1 else set())  # the fit: 1σ beyond the bound
    if factor < 1:  # 1σ inside the bound: kept and predicted from
        assert caveat is None
    else:  # 1σ beyond: held by the fit, and withheld, naming exactly those parameters
        assert caveat is not None and "a.tx" in caveat and "a.rx" in caveat
        assert "b.ty" not in caveat
    # the one bound, parameter by parameter
    assert list(beyond_placement(np.sqrt(np.diag(cov)), UNITS)) == [factor > 1] * 2 + [False]


def test_the_rule_is_said_in_one_wording():
    assert WeakBound(*PLACEMENT_BOUND).describe() == "20 mm / 0.1 rad (1σ)"
    msg = prediction_caveat(NAMES, UNITS, np.diag([(0.03) ** 2, 1e-6, 1e-10]))
    assert msg is not None and "1 identified parameter is beyond 20 mm / 0.1 rad (1σ)" in msg
