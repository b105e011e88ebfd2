"""Chunked batched solves and sensitivities equal the one-chunk results; log3 batched."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import pincal
from pincal.model.batch import _batch_fk
from pincal.model.batch._batch_ops import jlog3_batch, log3_batch
from pincal.sensitivity.batch import _batch_jacobian
from pincal.sensitivity.batch._batch_jacobian import sensitivities_batch


@pytest.mark.parametrize("name", ["stewart_6ups", "pkm5", "ur10"])
def test_chunked_equals_unchunked(name, monkeypatch):
    mech = pincal.load_mechanism(name)
    params = pincal.parameters(mech, "full")
    rows = pincal.sample_actuators(mech, 11, np.random.default_rng(3))
    values = 1e-4 * np.random.default_rng(4).standard_normal(len(params))
    at = params.apply(mech, values)
    Q1, bk1 = at.configurations_batch(rows)
    s1 = sensitivities_batch(at, params, Q1, bk1, values)
    monkeypatch.setattr(_batch_fk, "CHUNK", 4)
    monkeypatch.setattr(_batch_jacobian, "CHUNK", 4)
    Q2, bk2 = at.configurations_batch(rows)
    s2 = sensitivities_batch(at, params, Q2, bk2, values)
    np.testing.assert_allclose(Q2, Q1, atol=1e-12)
    np.testing.assert_allclose(s2.jacobian, s1.jacobian, atol=1e-12)
    np.testing.assert_allclose(s2.positions, s1.positions, atol=1e-12)
    if bk1.closure_jacobian is not None:
        np.testing.assert_allclose(bk2.closure_jacobian, bk1.closure_jacobian, atol=1e-12)
        _, Jc = at.closure_terms_batch(at.kinematics_batch(Q2), columns=at.free_dofs)
        np.testing.assert_allclose(bk2.closure_jacobian, Jc, atol=1e-12)


def test_closure_terms_columns_subset():
    mech = pincal.load_mechanism("pkm5")
    Q = mech.configurations(pincal.sample_actuators(mech, 4, np.random.default_rng(5)))
    bk = mech.kinematics_batch(Q)
    r, J = mech.closure_terms_batch(bk)
    cols = mech.free_dofs[::2]
    r2, J2 = mech.closure_terms_batch(bk, columns=cols)
    np.testing.assert_array_equal(r2, r)
    np.testing.assert_allclose(J2, J[:, :, cols], atol=1e-15)


@pytest.mark.parametrize(
    "angle", [0.0, 1e-9, 1e-6, 1e-4, 1e-3, 5e-3, 0.0099, 0.0101, 0.1, 1.0, 2.4, 2.6, 3.0, np.pi]
)
def test_log3_and_jlog3_batched_match_pinocchio(angle):
    rng = np.random.default_rng(int(angle * 1e6) % 1000)
    axes = rng.standard_normal((5, 3))
    w = angle * axes / np.linalg.norm(axes, axis=1, keepdims=True)
    R = np.array([pin.exp3(x) for x in w])
    L = log3_batch(R)
    Jl = jlog3_batch(L)
    for i in range(len(R)):
        np.testing.assert_allclose(L[i], pin.log3(R[i]), atol=1e-15)
        # pin.Jlog3 itself is off by ~1e-10 near 1e-3 rad (checked in long double)
        np.testing.assert_allclose(Jl[i], pin.Jlog3(R[i]), atol=1e-10)
