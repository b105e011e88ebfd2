"""Batched loop closing and sensitivities of non-square passive closure systems.

Machines written in other people's habits: redundant closure rows (an MJCF four-bar
cut by a ``connect``, a Delta whose parallelograms are closed by ``6d`` cuts) and
idle passive motion (a Delta whose rods end in MJCF ball joints, an RSSR whose ball
joint is emulated by three revolutes). The batched solve must close every pose the
pose-by-pose solver closes, to the same measured pose and on the same branch, and the
batched identification Jacobian (with closure breaking) must equal the pose-by-pose
one at the same configurations.
"""

from __future__ import annotations

import numpy as np
import pytest

import pincal
from pincal.model.batch._range_factor import RangeFactor
from pincal.sensitivity import pose_sensitivity
from pincal.sensitivity.batch._batch_jacobian import batch_applies, sensitivities_batch
from tests.open_world import machines


def _write(tmp_path_factory, fn):
    urdf, sidecar = fn()
    folder = tmp_path_factory.mktemp(fn.__name__)
    return machines.write_machine(folder, fn.__name__, urdf, sidecar)


@pytest.fixture(
    scope="module",
    params=["mjcf_fourbar", "mjcf_fivebar", "mjcf_delta", "delta_4r", "rssr_emulated_ball"],
)
def mech(request, tmp_path_factory):
    name = request.param
    if name.startswith("mjcf_"):
        return pincal.load_mechanism(machines.MJCF / f"{name[5:]}.xml")
    return pincal.load_mechanism(_write(tmp_path_factory, getattr(machines, name)))


def test_non_square_and_batch_solvable(mech):
    rows, k = mech.n_closure_rows, mech.free_dofs.size
    assert rows != k
    assert mech.batch_solvable and batch_applies(mech)


def test_batched_solve_closes_like_pose_by_pose(mech):
    rows = pincal.sample_actuators(mech, 40, np.random.default_rng(5))
    Q, ok, bk = mech.try_configurations_batch(rows)
    assert bk is not None and ok.mean() >= 0.9  # the batch does the work, not the fallback
    Q, bk = mech.configurations_batch(rows)
    for i, row in enumerate(rows):
        residual = np.max(np.abs(mech.closure_residual(Q[i])))
        assert residual <= 1e-14  # polished, as the pose-by-pose solve
        ref = mech.configuration(row)
        # same measured pose (idle joints and 2π turns may differ: the same assembly)
        got, want = mech.frame_placement(Q[i]), mech.frame_placement(ref)
        np.testing.assert_allclose(got.translation, want.translation, atol=1e-10)
        np.testing.assert_allclose(got.rotation, want.rotation, atol=1e-10)
    assert np.all(bk.closure_factor.sign() == mech.idle_branch)


@pytest.mark.parametrize("at_values", [False, True])
def test_batched_sensitivity_matches_pose_by_pose(mech, at_values):
    # at zero: every parameter (some break closure); elsewhere: the identifiable ones
    params = pincal.parameters(mech, "base" if at_values else "full")
    rng = np.random.default_rng(9)
    values = 2e-4 * rng.standard_normal(len(params)) if at_values else np.zeros(len(params))
    at = params.apply(mech, values)
    qs, bk = at.configurations_batch(pincal.sample_actuators(at, 12, rng))
    batch = sensitivities_batch(at, params, qs, bk, values)
    scale = max(1.0, float(np.max(np.abs(batch.jacobian))))
    breaks = np.zeros(len(params), dtype=bool)
    for i, q in enumerate(qs):
        ref = pose_sensitivity(at, params, q, values)
        np.testing.assert_allclose(batch.positions[i], ref.position, atol=1e-12)
        np.testing.assert_allclose(batch.jacobian[i], ref.jacobian, rtol=0, atol=1e-11 * scale)
        breaks |= ref.breaks_closure
    np.testing.assert_array_equal(batch.breaks_closure, breaks)
    if not at_values:
        assert breaks.any() == (mech.n_closure_rows > mech.closure_rank)


@pytest.mark.parametrize("shape", [(7, 4), (3, 5), (30, 18), (18, 24)])
def test_range_factor_is_the_pseudo_inverse(shape):
    rng = np.random.default_rng(sum(shape))
    m, k = shape
    J = rng.standard_normal((6, m, k))
    r = min(m, k)
    block = (np.arange(r), np.arange(r))
    f = RangeFactor.of(J, block)
    pinv = np.linalg.pinv(J)
    b, g = rng.standard_normal((6, m, 2)), rng.standard_normal((6, k, 3))
    np.testing.assert_allclose(f.solve(b), pinv @ b, atol=1e-10)
    np.testing.assert_allclose(f.solve_transposed(g), np.swapaxes(pinv, 1, 2) @ g, atol=1e-10)
    s_min = np.linalg.svd(J, compute_uv=False)[:, -1]
    assert np.all(f.inverse_norm_bound() * s_min >= 1 - 1e-12)
    np.testing.assert_array_equal(f.sign(), np.sign(np.linalg.det(J[:, :r, :r])))
    B = rng.standard_normal((6, m, 5))
    outside = B - J @ (pinv @ B)
    np.testing.assert_allclose(f.out_of_range(B), np.linalg.norm(outside, axis=1), atol=1e-10)
    assert not f.singular.any()


def test_range_factor_flags_rows_it_cannot_factor():
    J = np.random.default_rng(0).standard_normal((3, 5, 3))
    J[1, :, 2] = 0.0  # rank 2 < 3
    J[2, 0, 0] = np.nan
    f = RangeFactor.of(J, None)
    np.testing.assert_array_equal(f.singular, [False, True, True])
    np.testing.assert_array_equal(f.sign(), [0.0, 0.0, 0.0])  # no branch block given
    assert np.all(np.isfinite(f.solve(np.ones((3, 5, 1)))))


def test_open_world_benchmark_runs(tmp_path):
    """scripts/bench_open_world.py (a README command the suite does not run) still works."""
    import importlib.util
    from pathlib import Path

    path = Path(__file__).parents[2] / "scripts" / "bench_open_world.py"
    spec = importlib.util.spec_from_file_location("bench_open_world", path)
    assert spec is not None and spec.loader is not None
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    found = bench._machines(tmp_path)
    assert len(found) == 16 and all(Path(p).exists() for p in found.values())
    r = bench.bench(found["mjcf fourbar"], 20, 1)
    assert r["shape"] == "3×2" and r["in_batch"] == 1.0 and r["pose"] > 0 and r["batch"] > 0
