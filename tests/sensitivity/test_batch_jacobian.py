"""The batched identification Jacobian equals pose_sensitivity pose by pose (1e-12)."""

from __future__ import annotations

import numpy as np
import pytest

import pincal
from pincal.sensitivity import pose_sensitivity
from pincal.sensitivity.batch._batch_jacobian import batch_applies, sensitivities_batch

MODELS = ["stewart_6ups", "hexaslide_6pus", "pkm5", "wedge3", "aacmm", "ur10"]


@pytest.fixture(scope="module", params=MODELS)
def mech(request):
    return pincal.load_mechanism(request.param)


@pytest.mark.parametrize("at_values", [False, True])
def test_batch_sensitivity_matches_pose_sensitivity(mech, at_values):
    params = pincal.parameters(mech, "full")
    rng = np.random.default_rng(7)
    values = 1e-3 * rng.standard_normal(len(params)) if at_values else np.zeros(len(params))
    at = params.apply(mech, values) if at_values else mech
    assert batch_applies(at)
    rows = pincal.sample_actuators(at, 6, rng)
    qs, bk = at.configurations_batch(rows)
    batch = sensitivities_batch(at, params, qs, bk, values)
    scale = max(1.0, float(np.max(np.abs(batch.jacobian))))
    for i, q in enumerate(qs):
        ref = pose_sensitivity(at, params, q, values)
        np.testing.assert_allclose(batch.positions[i], ref.position, atol=1e-12)
        np.testing.assert_allclose(batch.rotations[i], ref.rotation, atol=1e-12)
        np.testing.assert_allclose(batch.jacobian[i], ref.jacobian, rtol=0, atol=1e-12 * scale)
    assert not batch.breaks_closure.any()


def test_batch_jacobian_matches_finite_differences():
    mech = pincal.load_mechanism("stewart_6ups")
    params = pincal.parameters(mech, "stewart42")
    rows = pincal.sample_actuators(mech, 3, np.random.default_rng(8))
    qs, bk = mech.configurations_batch(rows)
    J = sensitivities_batch(mech, params, qs, bk).jacobian
    h = 1e-6
    for k in (0, 7, 20, 41):
        d = np.zeros(len(params))
        d[k] = h
        plus, minus = params.apply(mech, d), params.apply(mech, -d)
        for i, row in enumerate(rows):
            pp = plus.frame_placement(plus.configuration(row, qs[i])).translation
            pm = minus.frame_placement(minus.configuration(row, qs[i])).translation
            np.testing.assert_allclose(J[i, :3, k], (pp - pm) / (2 * h), atol=1e-7)


def test_over_constrained_batched_with_closure_breaking():
    from pincal.model import Mechanism
    from tests.sensitivity.five_bar import FIVE_BAR_SIDECAR, FIVE_BAR_URDF

    mech = Mechanism(FIVE_BAR_URDF, FIVE_BAR_SIDECAR)
    params = pincal.parameters(mech, "full")
    assert mech.n_closure_rows > mech.closure_rank  # a 6d closure of a planar loop
    assert batch_applies(mech)
    rows = mech.actuators_of(mech.q_home) + np.array([[0.0, 0.0], [0.05, -0.03]])
    qs, bk = mech.configurations_batch(rows)
    batch = sensitivities_batch(mech, params, qs, bk)
    breaks = np.zeros(len(params), dtype=bool)
    for i, q in enumerate(qs):
        ref = pose_sensitivity(mech, params, q)
        np.testing.assert_allclose(batch.jacobian[i], ref.jacobian, atol=1e-12)
        breaks |= ref.breaks_closure
    assert breaks.any()
    np.testing.assert_array_equal(batch.breaks_closure, breaks)
