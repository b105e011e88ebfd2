"""Pose selection decides full rank by the rule of every command (unit columns first).

A parameter whose column is 1e-9 of the others (a unit or lever-arm choice) is
identifiable for ``info`` and identification (:func:`pincal.sensitivity.jacobian_rank`);
the selection's scores must not call every design rank-deficient because of it.
"""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from pincal.design import exchange, greedy, observability
from pincal.sensitivity import full_jacobian_ranks, jacobian_rank, numerical_rank


def _blocks(seed: int = 0, small: float = 1e-9) -> np.ndarray:
    """Candidate blocks (40, 3, 6) whose last parameter's column is ``small`` of the rest."""
    J = np.random.default_rng(seed).standard_normal((40, 3, 6))
    J[:, :, -1] *= small
    return J


def test_tiny_column_is_full_rank_for_every_rule():
    J = _blocks()
    stacked = J.reshape(-1, 6)
    s = np.linalg.svd(stacked, compute_uv=False)
    assert numerical_rank(s) == 5  # the unscaled singular values alone say deficient
    assert jacobian_rank(stacked) == 6
    assert observability(J).rank == 6 and observability(J).O1 > 0.0


def test_selection_scores_use_the_unit_column_rule():
    J = _blocks()
    for index in ("O1", "O2", "O3", "O4", "O5", "A"):
        sel = exchange(J, 6, index, rng=0, fast=False)
        assert sel.value > 0.0, index
        assert jacobian_rank(J[sel.indices].reshape(-1, 6)) == 6
        assert greedy(J, 6, index).value > 0.0, index


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    rows=st.integers(2, 9),
    spread=st.floats(-12.0, 0.0),
    deficient=st.booleans(),
)
def test_batched_decision_equals_jacobian_rank(seed, rows, spread, deficient):
    rng = np.random.default_rng(seed)
    J = rng.standard_normal((8, rows, 4)) * 10.0 ** rng.uniform(spread, 0.0, size=4)
    if deficient:
        J[::2, :, 3] = J[::2, :, 0] * 3.0 + 1e-9 * rng.standard_normal((4, rows))
    s = np.linalg.svd(J, compute_uv=False)
    got = full_jacobian_ranks(J, s)
    assert got.tolist() == [jacobian_rank(j) == 4 for j in J]
