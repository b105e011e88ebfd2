"""One rule for a parameter the poses do not place (issue 36): the fit's hold and
`validate`'s withheld prediction both read :data:`pincal.sensitivity.PLACEMENT_BOUND`
(1σ beyond 20 mm / 0.1 rad), so a parameter at the boundary is treated alike by both."""

from __future__ import annotations

import numpy as np
import pytest

from pincal.identification._fit_set import WeakBound
from pincal.sensitivity import PLACEMENT_BOUND, beyond_placement
from pincal.validation import prediction_caveat

NAMES, UNITS = ("a.tx", "a.rx", "b.ty"), ("m", "rad", "m")


def _whitened(std: np.ndarray) -> np.ndarray:
    """A whitened Jacobian (N, 3) whose parameters have the 1σ ``std`` and no correlation."""
    q, _ = np.linalg.qr(np.random.default_rng(0).normal(size=(40, 3)))
    return q / std  # orthogonal columns: (JᵀJ)⁻¹ = diag(std²)


@pytest.mark.parametrize("factor", [0.9, 0.999, 1.001, 1.1])
def test_fit_and_validate_agree_at_the_boundary(factor):
    length, angle = PLACEMENT_BOUND
    std = np.array([factor * length, factor * angle, 1e-5])  # b.ty well placed
    Jw = _whitened(std)
    held = WeakBound(length, angle).held(Jw, np.arange(3), UNITS, 3)
    cov = np.linalg.inv(Jw.T @ Jw)
    caveat = prediction_caveat(NAMES, UNITS, cov)
    if factor < 1:  # kept by the fit, and the prediction is given
        assert held.size == 0
        assert caveat is None
    else:  # held by the fit; a covariance that still had them makes validate withhold
        assert set(held) == {0, 1}
        assert caveat is not None and "a.tx" in caveat and "a.rx" in caveat
        assert "b.ty" not in caveat
    # the one rule, parameter by parameter
    assert list(beyond_placement(np.sqrt(np.diag(cov)), UNITS)) == [factor > 1] * 2 + [False]


def test_the_rule_is_said_in_one_wording():
    assert WeakBound(*PLACEMENT_BOUND).describe() == "20 mm / 0.1 rad (1σ)"
    msg = prediction_caveat(NAMES, UNITS, np.diag([(0.03) ** 2, 1e-6, 1e-10]))
    assert msg is not None and "1 identified parameters are beyond 20 mm / 0.1 rad (1σ)" in msg
