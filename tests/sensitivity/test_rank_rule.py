"""One rank rule: identifiability's base set always has as many members as the rank."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pincal.design import numerical_rank as design_numerical_rank
from pincal.errors import PincalError
from pincal.sensitivity import RANK_RTOL, RangeSolver, analyse_jacobian, numerical_rank


def _reproduces(J: np.ndarray, ident, tol: float) -> None:
    """Every non-base column equals Σ β · base columns with the reported β."""
    for k in ident.unidentifiable:
        combo = ident.combinations.get(int(k), {})
        rebuilt = sum((b * J[:, i] for i, b in combo.items()), np.zeros(J.shape[0]))
        scale = max(float(np.linalg.norm(J[:, k])), 1e-300)
        assert np.linalg.norm(J[:, k] - rebuilt) <= tol * scale, (k, combo)


def test_near_dependent_column_base_size_equals_rank():
    """σ3/σ1 ≈ 1e-6: above the rank threshold 1e-8, so 3 base parameters, not 2.

    (Before: rank by σ > 1e-8·σ1 = 3 but a greedy base by a 1e-4 residual = 2 members.)
    """
    rng = np.random.default_rng(0)
    q, _ = np.linalg.qr(rng.standard_normal((30, 3)))
    a, b, w = q.T
    c = (a + b) / np.sqrt(2.0) + 1e-6 * w
    J = np.column_stack([a, b, c]) * [1.0, 2.0, 0.5]
    ident = analyse_jacobian(J, ("a", "b", "c"))
    assert ident.rank == 3
    assert len(ident.base) == ident.rank
    assert ident.base.tolist() == [0, 1, 2]


def test_exact_dependent_column_is_absorbed():
    rng = np.random.default_rng(1)
    a, b = rng.standard_normal((2, 30))
    J = np.column_stack([a, b, 2.0 * a - 3.0 * b])
    ident = analyse_jacobian(J, ("a", "b", "c"))
    assert ident.rank == len(ident.base) == 2
    assert ident.combinations[2] == pytest.approx({0: 2.0, 1: -3.0}, rel=1e-9)


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    rank=st.integers(0, 7),
    n=st.integers(1, 14),
    zero_columns=st.integers(0, 2),
    breaking=st.integers(0, 3),
)
def test_random_rank_deficient_matrices(seed, rank, n, zero_columns, breaking):
    rng = np.random.default_rng(seed)
    rank = min(rank, n)
    rows = 40
    J = rng.standard_normal((rows, rank)) @ rng.standard_normal((rank, n))
    J *= 10.0 ** rng.uniform(-3, 3, n)  # mixed units
    J[:, rng.choice(n, size=min(zero_columns, n), replace=False)] = 0.0
    names = tuple(f"p{i}" for i in range(n))
    breaks = rng.choice(n, size=min(breaking, n), replace=False)
    for mask in (None, breaks):
        ident = analyse_jacobian(J, names, breaks_closure=mask)
        assert len(ident.base) == ident.rank
        keep = np.setdiff1d(np.arange(n), [] if mask is None else mask)
        true_rank = np.linalg.matrix_rank(J[:, keep]) if keep.size else 0
        assert ident.rank == true_rank
        assert sorted([*ident.base, *ident.unidentifiable, *ident.breaks_closure]) == list(range(n))
        if ident.rank:
            assert np.linalg.matrix_rank(J[:, ident.base]) == ident.rank
        _reproduces(J, ident, 1e-5)


def test_rank_rule_is_one_function():
    s = np.array([1.0, 1e-3, 1e-7, 1e-9, 0.0])
    assert numerical_rank(s) == 3 and RANK_RTOL == 1e-8
    assert numerical_rank(s, 1e-2) == 1
    assert numerical_rank([]) == 0 and numerical_rank([0.0, 0.0]) == 0
    assert design_numerical_rank is numerical_rank
    with pytest.raises(PincalError, match="rtol"):
        numerical_rank(s, -1.0)


def test_range_solver_one_factorisation_many_columns():
    rng = np.random.default_rng(4)
    A = rng.standard_normal((6, 3)) @ rng.standard_normal((3, 4))  # rank 3, 6 × 4
    B_in = A @ rng.standard_normal((4, 5))
    B_out = rng.standard_normal((6, 2))
    solver = RangeSolver.factor(A)
    assert solver.rank == 3
    X = solver.solve(B_in)
    np.testing.assert_allclose(A @ X, B_in, atol=1e-12)
    np.testing.assert_allclose(X, np.linalg.pinv(A) @ B_in, atol=1e-12)
    assert np.all(solver.out_of_range(B_in) < 1e-12)
    assert np.all(solver.out_of_range(B_out) > 1e-3)


def test_base_prefers_a_well_conditioned_column_to_a_barely_independent_one():
    """In set order a column whose part outside the span of the earlier ones is below
    BASE_RTOL·σ1 (here 1e-7) is passed over for a later, independent one: the same rank,
    a base conditioned like the problem rather than like that column (the 2-RSU ankle's
    `full` set took a rod-end offset at 1e-6 of σ1; Gauss–Newton then went 48 mm off)."""
    e = np.eye(3)
    J = np.column_stack([e[0], e[1], e[0] + 1e-7 * e[2], e[2]])
    ident = analyse_jacobian(J, ("a", "b", "barely", "d"))
    assert ident.rank == 3
    assert ident.base_names == ("a", "b", "d")
    assert ident.unidentifiable_names == ("barely",)
