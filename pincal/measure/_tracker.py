"""Laser-tracker measurement model: rigid best fits of SMR targets and their noise.

A laser tracker measures the 3D position of spherically mounted retroreflectors
(SMRs) in its own frame. A pose is never measured directly: several targets with
known coordinates on a rigid body (the machine base, a moving platform) are
measured and the body's pose is the best rigid fit of the known coordinates onto
the measured points (Kabsch / Umeyama without scale). The base is measured once
("registration") so that platform poses can be expressed in the machine's base
frame.

Frames and conventions (see docs/design.md, "Units, frames and names"): ``T_a_b`` is
the pose of frame ``b`` in frame ``a``; it maps ``b`` coordinates to ``a`` coordinates,
``p_a = R_a_b @ p_b + t_a_b``. Pose errors are local twists
``xi = log6(T_true^-1 * T_estimated)`` (linear part first, pinocchio order), the
same convention as the pose residuals of the identification.

Noise model: the Leica AT960 class maximum permissible error of a point
coordinate is ``±(15 µm + 6 µm/m)``. We read an MPE as a 2σ bound (the usual
reading of a manufacturer's "typical/MPE" figure for the ISO 10360-10 test) and
use an isotropic per-coordinate standard deviation ``σ(d) = a + b·d`` with
``a = 7.5 µm`` and ``b = 3 µm/m``, ``d`` the tracker-to-target distance. Real
trackers are anisotropic (the interferometric range is better than the angular
encoders); an isotropic model is a conservative, simple default.

All lengths are metres, angles radians.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from pincal.errors import MeasurementError, MovedTargetError

__all__ = [
    "LaserTracker",
    "PoseMeasurement",
    "RigidFit",
    "TrackerNoise",
    "fit_rigid_transform",
    "pose_from_target_points",
    "rigid_fit_covariance",
]

_log = logging.getLogger(__name__)

#: Relative threshold on the second singular value of the centred target cloud
#: below which the targets count as collinear (rotation about the line undefined).
COLLINEAR_RTOL = 1e-7


@dataclass(frozen=True, eq=False)
class RigidFit:
    """Result of a rigid best fit of local points onto measured points.

    Attributes:
        T: pose mapping local to measured coordinates, ``p_meas ≈ T.act(p_local)``.
        residual_vectors: (n, 3) ``p_meas - T.act(p_local)`` [m], measured frame.
        residuals: (n,) per-point residual distances [m].
        rms: root mean square of ``residuals`` [m] (unweighted).
    """

    T: pin.SE3
    residual_vectors: np.ndarray
    residuals: np.ndarray
    rms: float

    @property
    def max_residual(self) -> float:
        """Largest per-point residual distance [m]."""
        return float(self.residuals.max())


def _as_points(points: np.ndarray, name: str) -> np.ndarray:
    arr = np.asarray(points, dtype=float)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise MeasurementError(f"{name} must have shape (n, 3), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        bad = int(np.argwhere(~np.isfinite(arr))[0, 0])
        raise MeasurementError(f"{name} contains NaN or inf (row {bad})")
    return arr


def _as_weights(weights: np.ndarray | None, n: int) -> np.ndarray:
    if weights is None:
        return np.ones(n)
    w = np.asarray(weights, dtype=float)
    if w.shape != (n,):
        raise MeasurementError(f"weights must have shape ({n},), got {w.shape}")
    if not np.all(np.isfinite(w)) or np.any(w <= 0.0):
        raise MeasurementError("weights must be finite and positive")
    return w


def _check_not_collinear(points: np.ndarray, weights: np.ndarray, name: str) -> None:
    centred = points - weights @ points / weights.sum()
    s = np.linalg.svd(centred * np.sqrt(weights)[:, None], compute_uv=False)
    if s[0] == 0.0 or s[1] <= COLLINEAR_RTOL * s[0]:
        raise MeasurementError(
            f"{name}: the {len(points)} targets are coincident or collinear; a rigid fit "
            "needs at least 3 non-collinear targets"
        )


def kabsch(p: np.ndarray, q: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(R (3, 3), t (3,)) minimising ``Σ w_k |R p_k + t - q_k|²``, unchecked.

    The closed form of :func:`fit_rigid_transform` without its checks, for callers
    that iterate on points already checked (shapes (n, 3), weights (n,) > 0).
    """
    w_sum = w.sum()
    p_mean = w @ p / w_sum
    q_mean = w @ q / w_sum
    H = (p - p_mean).T @ ((q - q_mean) * w[:, None])  # Σ w p̃ q̃ᵀ, (3, 3)
    U, _, Vt = np.linalg.svd(H)
    d = np.sign(np.linalg.det(Vt.T @ U.T))
    D = np.diag([1.0, 1.0, d if d != 0.0 else 1.0])
    R = Vt.T @ D @ U.T
    return R, q_mean - R @ p_mean


def fit_rigid_transform(
    points_local: np.ndarray,
    points_measured: np.ndarray,
    weights: np.ndarray | None = None,
    max_residual: float | None = None,
) -> RigidFit:
    """Best rigid transform (rotation with det +1, translation) of local onto measured points.

    Minimises ``Σ w_k |R p_k + t - q_k|²`` in closed form (Kabsch/SVD, reflection
    excluded). With ``w_k = 1/σ_k²`` this is the maximum-likelihood fit for
    independent isotropic Gaussian noise on the measured points.

    Args:
        points_local: (n, 3) target coordinates in the body's own frame [m].
        points_measured: (n, 3) the same targets as measured [m].
        weights: (n,) positive weights, default all 1.
        max_residual: if given, raise :class:`MovedTargetError` when a target's
            residual distance exceeds it [m].

    Returns:
        A :class:`RigidFit` whose ``T`` maps local to measured coordinates.

    Raises:
        MeasurementError: bad shapes, NaN, fewer than 3 or collinear targets.
        MovedTargetError: a residual exceeds ``max_residual``.
    """
    p = _as_points(points_local, "points_local")
    q = _as_points(points_measured, "points_measured")
    if p.shape != q.shape:
        raise MeasurementError(
            f"points_local {p.shape} and points_measured {q.shape} must have the same shape"
        )
    n = p.shape[0]
    if n < 3:
        raise MeasurementError(f"a rigid fit needs at least 3 targets, got {n}")
    w = _as_weights(weights, n)
    _check_not_collinear(p, w, "points_local")
    R, t = kabsch(p, q, w)
    T = pin.SE3(R, t)

    res_vec = q - (p @ R.T + t)
    res = np.linalg.norm(res_vec, axis=1)
    fit = RigidFit(
        T=T, residual_vectors=res_vec, residuals=res, rms=float(np.sqrt(np.mean(res**2)))
    )
    if max_residual is not None:
        k = int(np.argmax(res))
        if res[k] > max_residual:
            raise MovedTargetError(k, float(res[k]), float(max_residual))
    return fit


def rigid_fit_covariance(points_local: np.ndarray, sigmas: np.ndarray | float) -> np.ndarray:
    """Linearised covariance of a weighted rigid fit's pose, as a local twist.

    With the fitted pose written ``T_est = T_true · exp6(xi)``, ``xi = (v, ω)`` in
    the local (body) frame, a measured point moves by ``R (v - [p_k]× ω)``. For
    independent isotropic noise of standard deviation σ_k per coordinate and the
    fit weights ``1/σ_k²``, ``Cov(xi) = (Σ_k J_kᵀ J_k / σ_k²)⁻¹`` with
    ``J_k = [I, -[p_k]×]``. This is also the Cramér–Rao bound of the pose.

    Args:
        points_local: (n, 3) target coordinates in the body frame [m].
        sigmas: scalar or (n,) per-coordinate standard deviations [m].

    Returns:
        (6, 6) covariance of ``xi`` [m², m·rad, rad²], linear part first.
    """
    p = _as_points(points_local, "points_local")
    n = p.shape[0]
    s = np.broadcast_to(np.asarray(sigmas, dtype=float), (n,))
    if np.any(s <= 0.0) or not np.all(np.isfinite(s)):
        raise MeasurementError("sigmas must be finite and positive")
    if n < 3:
        raise MeasurementError(f"a rigid fit needs at least 3 targets, got {n}")
    _check_not_collinear(p, 1.0 / s**2, "points_local")
    info = np.zeros((6, 6))
    for pk, sk in zip(p, s, strict=True):
        J = np.hstack([np.eye(3), -pin.skew(pk)])
        info += J.T @ J / sk**2
    return np.linalg.inv(info)


@dataclass(frozen=True)
class TrackerNoise:
    """Isotropic per-coordinate tracker noise ``σ(d) = a + b·d``.

    The defaults take the Leica AT960 MPE ``±(15 µm + 6 µm/m)`` as a 2σ bound.

    Attributes:
        a: constant part of σ [m].
        b: distance-proportional part of σ [m per m of distance].
    """

    a: float = 15e-6 / 2
    b: float = 6e-6 / 2

    def __post_init__(self) -> None:
        if not (self.a >= 0.0 and self.b >= 0.0) or self.a + self.b == 0.0:
            raise MeasurementError(
                f"tracker noise needs a >= 0, b >= 0, not both 0; got a={self.a}, b={self.b}"
            )

    def sigma(self, points_tracker: np.ndarray) -> np.ndarray:
        """Per-coordinate 1σ [m] of each point, shape (n,), from its distance to the tracker.

        Args:
            points_tracker: (n, 3) points in the tracker frame [m].
        """
        p = _as_points(points_tracker, "points_tracker")
        return self.a + self.b * np.linalg.norm(p, axis=1)

    def sample(self, points_tracker: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Noisy copies of points, shape (n, 3) [m], tracker frame."""
        p = _as_points(points_tracker, "points_tracker")
        return p + rng.standard_normal(p.shape) * self.sigma(p)[:, None]


@dataclass(frozen=True, eq=False)
class PoseMeasurement:
    """A body pose measured through targets, expressed in the machine base frame.

    Attributes:
        T_base_body: the fitted pose of the body in the base frame.
        fit: the rigid fit in the tracker frame (residuals, RMS).
        covariance: (6, 6) linearised covariance of this pose's own fit, as a local
            twist ``log6(T_true^-1 T_base_body)`` (linear first) — the part that is
            independent from pose to pose; use it to weight rows.
        covariance_with_registration: (6, 6) the same plus the base registration's
            uncertainty mapped into the body frame. The registration error is common
            to all poses (a systematic base-frame error), so it is not independent
            noise; it is absorbed by base-placement parameters.
    """

    T_base_body: pin.SE3
    fit: RigidFit
    covariance: np.ndarray
    covariance_with_registration: np.ndarray


def pose_from_target_points(
    registration: RigidFit,
    targets_body: np.ndarray,
    points_tracker: np.ndarray,
    noise: TrackerNoise,
    registration_covariance: np.ndarray | None = None,
    max_residual: float | None = None,
) -> PoseMeasurement:
    """Pose of a body in the base frame from its measured targets (real or simulated data).

    Args:
        registration: base registration, a fit whose ``T`` is ``T_tracker_base``.
        targets_body: (n, 3) target coordinates in the body frame [m].
        points_tracker: (n, 3) measured targets in the tracker frame [m].
        noise: the tracker noise model (fit weights ``1/σ²`` and covariance).
        registration_covariance: (6, 6) covariance of the registration as a local
            twist of ``T_tracker_base`` (from :func:`rigid_fit_covariance`); zero if None.
        max_residual: moved-target threshold [m], see :func:`fit_rigid_transform`.
    """
    pts = _as_points(points_tracker, "points_tracker")
    sig = noise.sigma(pts)
    fit = fit_rigid_transform(targets_body, pts, weights=1.0 / sig**2, max_residual=max_residual)
    T_base_body = registration.T.inverse() * fit.T
    cov = rigid_fit_covariance(targets_body, sig)
    cov_total = cov.copy()
    if registration_covariance is not None:
        # T_est = exp(-η)·T·exp(ξ) = T·exp(ξ - Ad(T⁻¹) η) to first order.
        Ad = T_base_body.inverse().toActionMatrix()
        cov_total = cov + Ad @ np.asarray(registration_covariance) @ Ad.T
    return PoseMeasurement(
        T_base_body=T_base_body, fit=fit, covariance=cov, covariance_with_registration=cov_total
    )


@dataclass(eq=False)
class LaserTracker:
    """Simulated laser tracker standing at a (true) placement relative to the machine base.

    The base frame is the world frame of the machine model. Typical use::

        tracker = LaserTracker(T_tracker_base, TrackerNoise())
        tracker.register_base(base_targets, rng)          # fits T_tracker_base
        m = tracker.measure_pose(T_world_platform, platform_targets, rng)
        m.T_base_body, m.covariance

    Attributes:
        T_tracker_base: true pose of the base in the tracker frame (simulation truth).
        noise: the noise model.
        registration: the last base registration (``fit.T`` estimates
            ``T_tracker_base``), or None before :meth:`register_base`.
        registration_covariance: (6, 6) its linearised covariance, or None.
    """

    T_tracker_base: pin.SE3
    noise: TrackerNoise = field(default_factory=TrackerNoise)
    registration: RigidFit | None = None
    registration_covariance: np.ndarray | None = None

    def measure_points(self, points_base: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Measure target points given in base (world) coordinates.

        Args:
            points_base: (n, 3) true target positions in the base frame [m].
            rng: random generator for the noise.

        Returns:
            (n, 3) noisy positions in the tracker frame [m].
        """
        p = _as_points(points_base, "points_base")
        T = self.T_tracker_base
        return self.noise.sample(p @ T.rotation.T + T.translation, rng)

    def register_base(
        self,
        targets_base: np.ndarray,
        rng: np.random.Generator,
        max_residual: float | None = None,
    ) -> RigidFit:
        """Measure the base targets and fit the tracker frame to the base frame.

        Stores and returns the fit (``fit.T`` estimates ``T_tracker_base``).

        Args:
            targets_base: (n, 3) nominal base target coordinates [m], n >= 3.
            rng: random generator for the noise.
            max_residual: moved-target threshold [m].
        """
        measured = self.measure_points(targets_base, rng)
        sig = self.noise.sigma(measured)
        fit = fit_rigid_transform(targets_base, measured, 1.0 / sig**2, max_residual)
        self.registration = fit
        self.registration_covariance = rigid_fit_covariance(targets_base, sig)
        _log.debug("base registration: %d targets, RMS %.2f µm", len(measured), fit.rms * 1e6)
        return fit

    def measure_pose(
        self,
        T_world_platform: pin.SE3,
        targets_platform: np.ndarray,
        rng: np.random.Generator,
        max_residual: float | None = None,
    ) -> PoseMeasurement:
        """Measure a platform pose through its targets, in the base frame.

        Args:
            T_world_platform: true pose of the platform in the base (world) frame.
            targets_platform: (n, 3) target coordinates in the platform frame [m].
            rng: random generator for the noise.
            max_residual: moved-target threshold [m].

        Raises:
            MeasurementError: the base has not been registered.
        """
        if self.registration is None:
            raise MeasurementError("register_base() must be called before measure_pose()")
        tp = _as_points(targets_platform, "targets_platform")
        R, t = T_world_platform.rotation, T_world_platform.translation
        measured = self.measure_points(tp @ R.T + t, rng)
        return pose_from_target_points(
            self.registration,
            tp,
            measured,
            self.noise,
            registration_covariance=self.registration_covariance,
            max_residual=max_residual,
        )
