"""Tests of the laser-tracker measurement model (pincal.measure._tracker)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from pincal.errors import MeasurementError, MovedTargetError
from pincal.measure import (
    LaserTracker,
    TrackerNoise,
    fit_rigid_transform,
    rigid_fit_covariance,
)

# Six SMR nests on a 0.2 m platform, centroid at the platform origin.
_ang = np.deg2rad([0.0, 60.0, 120.0, 180.0, 240.0, 300.0])
TARGETS = np.column_stack([0.1 * np.cos(_ang), 0.1 * np.sin(_ang), [0.02, -0.02] * 3])
TARGETS -= TARGETS.mean(axis=0)


def _random_se3(rng: np.random.Generator, scale: float = 1.0) -> pin.SE3:
    return pin.exp6(np.concatenate([scale * rng.normal(size=3), rng.normal(size=3)]))


def test_kabsch_recovers_known_transform_exactly():
    rng = np.random.default_rng(1)
    for _ in range(20):
        T = _random_se3(rng, 2.0)
        p = rng.normal(size=(5, 3))
        q = p @ T.rotation.T + T.translation
        fit = fit_rigid_transform(p, q)
        assert np.allclose(fit.T.homogeneous, T.homogeneous, atol=1e-12)
        assert np.linalg.det(fit.T.rotation) == pytest.approx(1.0, abs=1e-12)
        assert fit.rms < 1e-12
        assert fit.residuals.shape == (5,)


def test_reflection_is_excluded():
    # Measured points are a mirror image: the best proper rotation is not the mirror.
    rng = np.random.default_rng(2)
    p = rng.normal(size=(6, 3))
    q = p * np.array([1.0, 1.0, -1.0])
    fit = fit_rigid_transform(p, q)
    assert np.linalg.det(fit.T.rotation) == pytest.approx(1.0)
    assert fit.rms > 0.1


def test_weighted_fit_is_weighted_least_squares():
    # A perturbed fit must not lower the weighted cost: compare to an independent optimiser.
    from scipy.optimize import minimize

    rng = np.random.default_rng(3)
    p = rng.normal(size=(7, 3))
    T = _random_se3(rng)
    q = p @ T.rotation.T + T.translation + 0.01 * rng.normal(size=(7, 3))
    w = rng.uniform(0.1, 5.0, size=7)
    fit = fit_rigid_transform(p, q, weights=w)

    def cost(xi):
        Tx = fit.T * pin.exp6(xi)
        r = q - (p @ Tx.rotation.T + Tx.translation)
        return float(w @ np.sum(r**2, axis=1))

    res = minimize(cost, np.zeros(6), method="BFGS", options={"gtol": 1e-12})
    assert np.linalg.norm(res.x) < 1e-5
    assert cost(np.zeros(6)) <= res.fun + 1e-12


def test_noise_statistics_match_analytic_expectation():
    # Constant σ: translation error of a centroid-origin fit has std σ/√n per axis,
    # E[rms²] = σ²(3n-6)/n, and the full twist covariance matches rigid_fit_covariance.
    rng = np.random.default_rng(4)
    sigma = 20e-6
    n = len(TARGETS)
    T = _random_se3(rng)
    trials = 3000
    errs = np.empty((trials, 6))
    rms2 = np.empty(trials)
    clean = TARGETS @ T.rotation.T + T.translation
    for k in range(trials):
        fit = fit_rigid_transform(TARGETS, clean + sigma * rng.standard_normal(clean.shape))
        errs[k] = pin.log6(T.inverse() * fit.T).vector
        rms2[k] = fit.rms**2
    std_t = errs[:, :3].std(axis=0)
    assert np.allclose(std_t, sigma / np.sqrt(n), rtol=0.06)
    assert rms2.mean() == pytest.approx(sigma**2 * (3 * n - 6) / n, rel=0.04)
    cov_pred = rigid_fit_covariance(TARGETS, sigma)
    assert np.allclose(np.diag(cov_pred)[:3], sigma**2 / n)
    # Mean Mahalanobis distance² of a 6-dof Gaussian error is 6.
    m2 = np.einsum("ki,ij,kj->k", errs, np.linalg.inv(cov_pred), errs)
    assert m2.mean() == pytest.approx(6.0, rel=0.05)
    cov_rot = cov_pred[3:, 3:]
    assert np.allclose(np.cov(errs.T)[3:, 3:], cov_rot, rtol=0.1, atol=0.05 * cov_rot.max())


def test_tracker_noise_model():
    noise = TrackerNoise()
    assert noise.a == pytest.approx(7.5e-6)
    assert noise.b == pytest.approx(3e-6)
    pts = np.array([[0.0, 0.0, 0.0], [3.0, 4.0, 0.0]])
    assert np.allclose(noise.sigma(pts), [7.5e-6, 7.5e-6 + 5 * 3e-6])
    rng = np.random.default_rng(5)
    far = np.tile([[0.0, 6.0, 8.0]], (20000, 1))  # 10 m away: σ = 37.5 µm
    d = noise.sample(far, rng) - far
    assert d.std() == pytest.approx(37.5e-6, rel=0.02)
    assert abs(d.mean()) < 1e-6
    with pytest.raises(MeasurementError):
        TrackerNoise(a=0.0, b=0.0)


def test_moved_target_is_flagged_by_index():
    rng = np.random.default_rng(6)
    T = _random_se3(rng)
    q = TARGETS @ T.rotation.T + T.translation + 5e-6 * rng.standard_normal(TARGETS.shape)
    fit_rigid_transform(TARGETS, q, max_residual=50e-6)  # clean data passes
    q[4] += [0.0, 0.3e-3, 0.0]  # nest 4 knocked by 0.3 mm
    with pytest.raises(MovedTargetError) as info:
        fit_rigid_transform(TARGETS, q, max_residual=50e-6)
    assert info.value.target_index == 4
    assert 0.1e-3 < info.value.residual < 0.3e-3
    assert "target 4" in str(info.value) and " mm" in str(info.value)
    assert isinstance(info.value, MeasurementError)


def test_collinear_and_too_few_points_raise():
    line = np.outer(np.linspace(0.0, 1.0, 5), [1.0, 2.0, 3.0])
    with pytest.raises(MeasurementError, match="collinear"):
        fit_rigid_transform(line, line)
    with pytest.raises(MeasurementError, match="at least 3"):
        fit_rigid_transform(TARGETS[:2], TARGETS[:2])
    with pytest.raises(MeasurementError, match=r"shape \(n, 3\)"):
        fit_rigid_transform(TARGETS[:, :2], TARGETS[:, :2])
    with pytest.raises(MeasurementError, match="same shape"):
        fit_rigid_transform(TARGETS, TARGETS[:4])
    bad = TARGETS.copy()
    bad[1, 1] = np.nan
    with pytest.raises(MeasurementError, match="NaN"):
        fit_rigid_transform(TARGETS, bad)


def test_laser_tracker_pose_in_base_frame():
    rng = np.random.default_rng(7)
    # Tracker 3 m from the machine, turned; base targets on a 1.2 m ring at floor level.
    T_tracker_base = pin.SE3(pin.rpy.rpyToMatrix(0.02, -0.01, 2.5), np.array([2.5, 1.0, -0.4]))
    ring = np.deg2rad(np.arange(0, 360, 45))
    base_targets = np.column_stack(
        [0.6 * np.cos(ring), 0.6 * np.sin(ring), 0.05 * np.cos(3 * ring)]
    )
    T_world_platform = pin.SE3(pin.rpy.rpyToMatrix(0.1, -0.2, 0.3), np.array([0.02, -0.03, 0.46]))

    tracker = LaserTracker(T_tracker_base, TrackerNoise())
    with pytest.raises(MeasurementError, match="register_base"):
        tracker.measure_pose(T_world_platform, TARGETS, rng)

    # Noise-free limit: exact pose.
    exact = LaserTracker(T_tracker_base, TrackerNoise(a=1e-15, b=0.0))
    exact.register_base(base_targets, rng)
    m = exact.measure_pose(T_world_platform, TARGETS, rng)
    assert np.allclose(m.T_base_body.homogeneous, T_world_platform.homogeneous, atol=1e-12)

    # Noisy: errors consistent with the predicted covariance including registration.
    trials = 1500
    m2_total = np.empty(trials)
    m2_fit = np.empty(trials)
    for k in range(trials):
        tracker.register_base(base_targets, rng)
        m = tracker.measure_pose(T_world_platform, TARGETS, rng)
        xi = pin.log6(T_world_platform.inverse() * m.T_base_body).vector
        m2_total[k] = xi @ np.linalg.solve(m.covariance_with_registration, xi)
        m2_fit[k] = xi @ np.linalg.solve(m.covariance, xi)
    assert m2_total.mean() == pytest.approx(6.0, rel=0.07)
    assert m2_fit.mean() > m2_total.mean()  # the registration adds error
    # Covariance of a 3 m measurement: σ ≈ 7.5 + 3·3 = 16.5 µm; translation σ/√6.
    sig = 7.5e-6 + 3e-6 * np.linalg.norm(T_tracker_base.translation)
    assert np.sqrt(m.covariance[0, 0]) == pytest.approx(sig / np.sqrt(6), rel=0.1)
