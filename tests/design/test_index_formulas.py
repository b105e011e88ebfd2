"""One implementation per index formula and per scaling, one rank rule for all."""

from __future__ import annotations

import numpy as np
import pytest

from pincal.design import (
    INDEX_NAMES,
    DesignScaling,
    batch_indices,
    dimensionless_rows,
    exchange,
    observability,
    scale_columns,
    weight_rows,
)
from pincal.design._scoring import ScoringProblem
from pincal.model import COMPONENTS


def _by_definition(s: np.ndarray, m: int) -> dict[str, float]:
    L = s.size
    return {
        "O1": float(np.prod(s) ** (1.0 / L) / np.sqrt(m)),
        "O2": float(s[-1] / s[0]),
        "O3": float(s[-1]),
        "O4": float(s[-1] ** 2 / s[0]),
        "O5": float(1.0 / np.sum(1.0 / s)),
        "A": float(1.0 / np.sum(s**-2.0)),
    }


def test_indices_follow_the_definitions_everywhere():
    rng = np.random.default_rng(0)
    J = rng.standard_normal((40, 6, 5))
    members = [0, 3, 7, 11, 19]
    s = np.linalg.svd(J[members].reshape(-1, 5), compute_uv=False)
    want = _by_definition(s, len(members))
    obs = observability(J[members])
    batch = batch_indices(s[None, :], len(members))
    for name in INDEX_NAMES:
        assert obs.get(name) == pytest.approx(want[name], rel=1e-12)
        assert batch[name][0] == pytest.approx(want[name], rel=1e-12)
        # the exchange algorithms score designs with the same formula
        problem = ScoringProblem(J, name, True, 64, 1e-9)
        assert problem.exact(members) == pytest.approx(want[name], rel=1e-12)
    sel = exchange(J, 5, "A", rng=1)
    assert sel.value == pytest.approx(observability(J[sel.indices]).get("A"), rel=1e-12)


def test_one_rank_rule_for_the_indices():
    """The rank is :func:`pincal.sensitivity.jacobian_rank` (unit columns, σ > 1e-8·σ1):
    a column dependent on the others to 1e-9 is rank-deficient, every index 0; a column
    merely 1e-9 as long as the others (a unit choice) is not."""
    u, _ = np.linalg.qr(np.random.default_rng(1).standard_normal((12, 3)))
    a, b, w = u.T
    J = np.column_stack([a, 0.5 * b, (a + b) / np.sqrt(2.0) + 1e-9 * w])
    obs = observability(J, m=4)
    assert obs.rank == 2 and not obs.full_rank
    assert all(v == 0.0 for v in obs.as_dict().values())
    near = np.column_stack([a, 0.5 * b, (a + b) / np.sqrt(2.0) + 1e-7 * w])
    assert observability(near, m=4).rank == 3
    tiny = observability(u * [1.0, 0.5, 1e-9], m=4)
    assert tiny.rank == 3 and tiny.O3 == pytest.approx(1e-9, rel=1e-6)


def test_design_scaling_is_the_row_and_column_functions():
    rng = np.random.default_rng(2)
    J = rng.standard_normal((7, 6, 4))
    K = 0.6
    np.testing.assert_array_equal(
        DesignScaling(rows="K", K=K).apply(J, COMPONENTS).J, dimensionless_rows(J, K).J
    )
    noise = DesignScaling(rows="noise", position_std=1e-5, orientation_std=2e-5, columns="norm")
    sigma = np.array([1e-5] * 3 + [2e-5] * 3)
    both = noise.apply(J, COMPONENTS)
    by_parts = scale_columns(weight_rows(J, sigma).J)
    np.testing.assert_allclose(both.J, by_parts.J, rtol=1e-15)
    np.testing.assert_allclose(both.col_scale, by_parts.col_scale, rtol=1e-15)
    std = np.array([1e-3, 2e-3, 1e-4, 5e-3])
    np.testing.assert_array_equal(
        DesignScaling(rows="none", columns="std", column_std=tuple(std)).apply(J, COMPONENTS).J,
        scale_columns(J, std).J,
    )
