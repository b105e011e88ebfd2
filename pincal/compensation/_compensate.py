"""Compensation: actuator commands that bring the *calibrated* model to target poses.

Compensation is inverse kinematics with the calibrated model: the commands for
which the identified machine (not the nominal one) reaches each target. Targets
are solved in order, each warm-started from the previous solution.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pincal.errors import ConvergenceError, MeasurementError
from pincal.model import Mechanism

__all__ = ["Compensation", "compensate", "poses_from_array"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Compensation:
    """Commands for a list of target poses.

    Attributes:
        q_act: (m, n_act) commands [m, rad]; rows of unreachable targets are NaN.
        reachable: (m,) bool.
        unreachable: indices of unreachable targets.
        reasons: message per unreachable index.
        actuated: actuated joint names (columns of ``q_act``).
    """

    q_act: np.ndarray
    reachable: np.ndarray
    unreachable: tuple[int, ...]
    reasons: dict[int, str]
    actuated: tuple[str, ...]

    @property
    def commands(self) -> np.ndarray:
        """(r, n_act) the rows of the reachable targets only."""
        return self.q_act[self.reachable]


def poses_from_array(poses: np.ndarray) -> list[pin.SE3]:
    """Poses from an (m, 6) array ``[x, y, z [m], rx, ry, rz [rad, rotation vector]]``.

    Args:
        poses: shape (m, 6) or (6,) [m, rad].

    Returns:
        m world-frame poses.

    Raises:
        MeasurementError: wrong shape, non-numeric, NaN or infinite values.
    """
    try:
        arr = np.atleast_2d(np.asarray(poses, dtype=float))
    except (TypeError, ValueError):
        raise MeasurementError(
            "target poses must be numbers, an (m, 6) array [x y z rx ry rz] (m, rad)"
        ) from None
    if arr.ndim != 2 or arr.shape[1] != 6:
        raise MeasurementError(f"target poses must be (m, 6) [x y z rx ry rz], got {arr.shape}")
    bad = np.nonzero(~np.all(np.isfinite(arr), axis=1))[0]
    if bad.size:
        raise MeasurementError(f"target pose {int(bad[0])} contains NaN or inf")
    return [pin.SE3(pin.exp3(r[3:]), r[:3].copy()) for r in arr]


def _as_poses(targets: Sequence[pin.SE3] | np.ndarray) -> list[pin.SE3]:
    if isinstance(targets, np.ndarray):
        return poses_from_array(targets)
    poses = list(targets)
    if all(isinstance(T, pin.SE3) for T in poses):
        return poses
    if any(isinstance(T, pin.SE3) for T in poses):
        raise MeasurementError(
            "targets mix pin.SE3 poses and other values; give all as pin.SE3 or an (m, 6) "
            "array [x y z rx ry rz] (m, rad)"
        )
    return poses_from_array(poses)


def compensate(
    calibrated: Mechanism,
    targets: Sequence[pin.SE3] | np.ndarray,
    check_limits: bool = True,
    progress: Callable[[int, int], None] | None = None,
) -> Compensation:
    """Actuator commands reaching ``targets`` with the calibrated model's inverse kinematics.

    Args:
        calibrated: the identified mechanism (e.g. ``IdentificationResult.calibrated``).
        targets: world-frame poses of the measured frame, as ``pin.SE3`` or an (m, 6)
            array ``[x y z [m], rx ry rz [rad]]``.
        check_limits: treat commands outside the actuator limits as unreachable.
        progress: optional callback ``(done, total)``.

    Returns:
        A :class:`Compensation`; unreachable targets are reported by index, not raised.

    Raises:
        MeasurementError: targets that are neither ``pin.SE3`` poses nor an (m, 6)
            array of finite numbers.
    """
    poses = _as_poses(targets)
    m, n = len(poses), calibrated.n_actuated
    q_act = np.full((m, n), np.nan)
    reasons: dict[int, str] = {}
    guess = None
    for i, T in enumerate(poses):
        try:
            q = calibrated.inverse_configuration(T, guess)
            row = calibrated.actuators_of(q)
            if check_limits:
                lo, hi = np.asarray(calibrated.actuator_limits, dtype=float).T
                out = np.nonzero((row < lo - 1e-12) | (row > hi + 1e-12))[0]
                if out.size:
                    k = int(out[0])
                    raise ConvergenceError(
                        f"needs {calibrated.actuated[k]} = {row[k]:.6g}, outside "
                        f"[{lo[k]:.6g}, {hi[k]:.6g}]"
                    )
            q_act[i] = row
            guess = q
        except ConvergenceError as exc:
            reasons[i] = str(exc)
            log.info("target %d unreachable: %s", i, exc)
        if progress:
            progress(i + 1, m)
    reachable = np.all(np.isfinite(q_act), axis=1)
    return Compensation(
        q_act, reachable, tuple(sorted(reasons)), reasons, tuple(calibrated.actuated)
    )
