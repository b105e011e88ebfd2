"""The batched point-closure Jacobian on a subset of columns (issue 36).

A closure that no requested column moves has zero Jacobian rows; the other closures
keep theirs. Before: one such closure dropped every closure's columns and, with two or
more point closures, crashed with a numpy broadcast error (shapes (3,6,1) (1,0,0) on
the MJCF delta; a URDF excavator-like arm with four planar loops failed the same way).
"""

from __future__ import annotations

import numpy as np
import pytest

from pincal.model import load_mechanism, sample_actuators
from tests.open_world import machines as m


@pytest.fixture(scope="module")
def delta():
    return load_mechanism(m.MJCF / "delta.xml")


def _support(mech) -> list[np.ndarray]:
    """Per closure, whether each tangent dof moves one of its frames (nv,) bool."""
    kernels = mech.batch_solver.kernels
    bm = kernels.batch_model
    fids = kernels.queries.closure_fids
    return [bm.support_of_frame(a) | bm.support_of_frame(b) for a, b in fids]


@pytest.mark.parametrize("pick", ["first_arm", "one_elbow", "mixed"])
def test_columns_moving_some_closures_only(delta, pick):
    support = _support(delta)
    assert all(c.is_point for c in delta.closures) and len(support) == 6
    others = [np.any([t for t in support if t is not s], axis=0) for s in support]
    only = [np.flatnonzero(s & ~o) for s, o in zip(support, others, strict=True)]
    cols = {
        "first_arm": np.array([0]),  # the first motor: closures 0 and 1
        "one_elbow": only[1],  # dofs moving closure 1 alone
        "mixed": np.r_[only[2], only[5]],
    }[pick]
    moved = np.array([s[cols].any() for s in support])
    assert moved.any() and not moved.all()
    rows = sample_actuators(delta, 4, np.random.default_rng(3))
    Q, _ = delta.configurations_batch(rows)
    bk = delta.kinematics_batch(Q)
    r, J = delta.closure_terms_batch(bk)
    r_sub, J_sub = delta.closure_terms_batch(bk, columns=cols)
    assert np.array_equal(r_sub, r)
    assert np.max(np.abs(J_sub - J[:, :, cols])) <= 1e-15
    for k, c in enumerate(moved):
        block = J_sub[:, 3 * k : 3 * k + 3]
        assert np.all(block == 0.0) if not c else np.abs(block).max() > 1e-6
