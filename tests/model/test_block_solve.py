"""The block solve of passive closure systems equals dense LAPACK (solve, transpose, sign)."""

from __future__ import annotations

import numpy as np
import pytest

import pincal
from pincal.model.batch._block_solve import BlockSolver, DenseFactor

MACHINES = ["stewart_6ups", "hexaslide_6pus", "pkm5", "wedge3", "tests/model/machines/rpr3"]


def _structure(shapes: list[tuple[int, int]], shared: int):
    """Row blocks and a support pattern: closure c has m rows, p private columns."""
    k = sum(m for m, _ in shapes)
    assert k == sum(p for _, p in shapes) + shared
    blocks, support, r0, c0 = [], np.zeros((k, k), dtype=bool), 0, 0
    for m, p in shapes:
        blocks.append(np.arange(r0, r0 + m))
        support[r0 : r0 + m, c0 : c0 + p] = True
        support[r0 : r0 + m, k - shared :] = True
        r0, c0 = r0 + m, c0 + p
    # scramble rows and columns so that the blocks are not contiguous
    rng = np.random.default_rng(len(shapes))
    rp, cp = rng.permutation(k), rng.permutation(k)
    inv_r = np.argsort(rp)
    return [inv_r[b] for b in blocks], support[rp][:, cp]


SHAPES = [
    ([(3, 2)] * 6, 6),  # Stewart-like
    ([(2, 1), (2, 1), (3, 2), (3, 2)], 4),  # mixed planar / spatial legs
    ([(3, 1)] * 3, 6),  # PRS-like: QR null bases
    ([(3, 0), (3, 3), (3, 2)], 4),  # a closure with no private column, one with all
]


@pytest.mark.parametrize(("shapes", "shared"), SHAPES)
def test_block_solve_equals_dense(shapes, shared):
    blocks, support = _structure(shapes, shared)
    solver = BlockSolver.build(blocks, support)
    assert solver is not None
    rng = np.random.default_rng(7)
    J = np.where(support, rng.standard_normal((400, *support.shape)), 0.0)
    k = support.shape[0]
    F, D = solver.factor(J), DenseFactor.of(J)
    b = rng.standard_normal((400, k, 3))
    ref = np.linalg.solve(J, b)
    scale = np.abs(ref).max(axis=(1, 2))[:, None, None]
    assert np.max(np.abs(F.solve(b) - ref) / scale) < 1e-9
    assert np.max(np.abs(F.solve(b[..., :1]) - ref[..., :1]) / scale) < 1e-9
    ref_t = np.linalg.solve(np.swapaxes(J, 1, 2), b)
    scale_t = np.abs(ref_t).max(axis=(1, 2))[:, None, None]
    assert np.max(np.abs(F.solve_transposed(b) - ref_t) / scale_t) < 1e-9
    signs = np.sign(np.linalg.det(J))
    assert set(signs) == {-1.0, 1.0}  # both branches are exercised
    np.testing.assert_array_equal(F.sign(), signs)
    np.testing.assert_array_equal(D.sign(), signs)
    true_norm = np.linalg.norm(np.linalg.inv(J), 2, axis=(1, 2))
    assert np.all(F.inverse_norm_bound() >= true_norm * (1 - 1e-12))
    assert np.all(D.inverse_norm_bound() >= true_norm * (1 - 1e-12))
    # a slice of the factors is the factor of the slice
    np.testing.assert_array_equal(F.take(slice(150, None)).solve(b[150:]), F.solve(b)[150:])
    np.testing.assert_array_equal(D.take(slice(150, None)).solve(b[150:]), D.solve(b)[150:])


def test_singular_block_is_flagged():
    blocks, support = _structure([(3, 2)] * 6, 6)
    solver = BlockSolver.build(blocks, support)
    assert solver is not None
    rng = np.random.default_rng(3)
    J = np.where(support, rng.standard_normal((5, *support.shape)), 0.0)
    g = solver.groups[0]
    J[2][:, g.cols[0, 1]] = J[2][:, g.cols[0, 0]]  # two private columns of a leg collinear
    J[4, 0, 0] = np.nan
    F = solver.factor(J)
    np.testing.assert_array_equal(F.singular, [False, False, True, False, True])
    assert F.sign()[2] == 0.0 and F.sign()[4] == 0.0


def test_structures_that_do_not_reduce():
    k = 6
    blocks = [np.arange(3), np.arange(3, 6)]
    assert BlockSolver.build(blocks, np.ones((k, k), dtype=bool)) is None  # all shared
    support = np.zeros((k, k), dtype=bool)
    support[:3, :4] = True  # four private columns for three rows
    support[3:, 4:] = True
    assert BlockSolver.build(blocks, support) is None
    assert BlockSolver.build([np.arange(3)], np.ones((3, 4), dtype=bool)) is None
    # one closure owning every column (a single loop): nothing shared to reduce
    assert BlockSolver.build([np.arange(3)], np.ones((3, 3), dtype=bool)) is None
    independent = np.zeros((k, k), dtype=bool)
    independent[:3, :3] = independent[3:, 3:] = True
    assert BlockSolver.build(blocks, independent) is None


@pytest.mark.parametrize("name", MACHINES)
def test_machines_use_blocks_and_keep_the_branch(name):
    mech = pincal.load_mechanism(name)
    assert mech.batch_solver.kernels.passive_solver is not None
    rows = pincal.sample_actuators(mech, 30, np.random.default_rng(4))
    Q, bk = mech.configurations_batch(rows)
    _, Jf = mech.closure_terms_batch(bk, columns=mech.free_dofs)
    for i, q in enumerate(Q):  # the free-column path equals Pinocchio's Jacobian
        np.testing.assert_allclose(Jf[i], mech.closure_jacobian(q)[:, mech.free_dofs], atol=1e-12)
    F = mech.passive_factor(Jf)
    np.testing.assert_array_equal(F.sign(), np.sign(np.linalg.det(Jf)))
    np.testing.assert_array_equal(F.sign(), mech.home_branch)
