"""Compensation: actuator commands that bring the *calibrated* model to target poses.

Compensation is inverse kinematics with the calibrated model: the commands for
which the identified machine (not the nominal one) reaches each target. Targets
are solved in order, each warm-started from the previous solution.

Only the components the machine controls are imposed: by default the model's
measured components (``mech.measured_components``, e.g. ``x z ry`` for the 3-DOF
wedge), or the ``components`` given. A machine of mobility n cannot meet more than
n independent components, so asking for more is refused with the reason.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from pincal.errors import ConvergenceError, MeasurementError, MobilityError, ModelFileError
from pincal.model import COMPONENTS, Mechanism

__all__ = ["Compensation", "compensate", "compensation_components", "poses_from_array"]

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
        components: the pose components imposed (subset of x y z rx ry rz).
    """

    q_act: np.ndarray
    reachable: np.ndarray
    unreachable: tuple[int, ...]
    reasons: dict[int, str]
    actuated: tuple[str, ...]
    components: tuple[str, ...] = COMPONENTS

    @property
    def commands(self) -> np.ndarray:
        """(r, n_act) the rows of the reachable targets only."""
        return self.q_act[self.reachable]


def poses_from_array(poses: ArrayLike) -> list[pin.SE3]:
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


def compensation_components(
    mech: Mechanism, components: Sequence[str] | str | None = None
) -> tuple[str, ...]:
    """The components a compensation of ``mech`` imposes, checked against its mobility.

    Args:
        mech: the (calibrated) mechanism.
        components: names from x y z rx ry rz (a sequence or ``"x,y,z"``); None: the
            model's measured components.

    Returns:
        The components in x y z rx ry rz order.

    Raises:
        MeasurementError: unknown or repeated component names.
        MobilityError: more components than the machine's mobility.
    """
    if components is None:
        comps = tuple(mech.measured_components)
        origin = "the model's measured components"
    else:
        names = components.replace(",", " ").split() if isinstance(components, str) else components
        names = [str(c).strip().lower() for c in names]
        bad = [c for c in names if c not in COMPONENTS]
        if bad or not names or len(set(names)) != len(names):
            raise MeasurementError(
                f"compensation components {list(names)} invalid; choose distinct names from "
                f"{' '.join(COMPONENTS)} (e.g. x,y,z)"
            )
        comps = tuple(c for c in COMPONENTS if c in names)
        origin = "the components asked for"
    if len(comps) > mech.mobility:
        raise MobilityError(
            f"{mech.name} has {mech.mobility} degrees of freedom but {origin} are "
            f"{len(comps)} ({' '.join(comps)}): a target cannot fix more components than the "
            f"machine moves; choose at most {mech.mobility} (CLI: --components, e.g. "
            f"{','.join(comps[: mech.mobility])})"
        )
    return comps


def _solver(mech: Mechanism, comps: tuple[str, ...]) -> Mechanism:
    """``mech`` itself, or a copy whose inverse kinematics imposes ``comps``."""
    if comps == tuple(mech.measured_components):
        return mech
    try:
        return Mechanism(
            mech.urdf_xml,
            mech.sidecar.replace(measured=list(comps)),
            name=mech.name,
            source=mech.source,
            measured_frame=mech.measured_frame,
            q_guess=mech.q_home,
            options=mech.options,
        )
    except ModelFileError as exc:  # pragma: no cover - comps are checked above
        raise MeasurementError(f"components {comps}: {exc}") from exc


def compensate(
    calibrated: Mechanism,
    targets: Sequence[pin.SE3] | np.ndarray,
    check_limits: bool = True,
    progress: Callable[[int, int], None] | None = None,
    components: Sequence[str] | str | None = None,
) -> Compensation:
    """Actuator commands reaching ``targets`` with the calibrated model's inverse kinematics.

    Args:
        calibrated: the identified mechanism (e.g. ``IdentificationResult.calibrated``).
        targets: world-frame poses of the measured frame, as ``pin.SE3`` or an (m, 6)
            array ``[x y z [m], rx ry rz [rad]]``.
        check_limits: treat commands outside the actuator limits as unreachable.
        progress: optional callback ``(done, total)``.
        components: the pose components to impose (see :func:`compensation_components`;
            default: the model's measured components).

    Returns:
        A :class:`Compensation`; unreachable targets are reported by index with the
        reason, not raised.

    Raises:
        MeasurementError: targets that are neither ``pin.SE3`` poses nor an (m, 6)
            array of finite numbers, or bad ``components``.
        MobilityError: more components than the machine's mobility.
    """
    poses = _as_poses(targets)
    comps = compensation_components(calibrated, components)
    solver = _solver(calibrated, comps)
    m, n = len(poses), calibrated.n_actuated
    q_act = np.full((m, n), np.nan)
    reasons: dict[int, str] = {}
    guess = None
    for i, T in enumerate(poses):
        try:
            q = solver.inverse_configuration(T, guess)
            row = solver.actuators_of(q)
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
            reasons[i] = f"{exc} (imposing {' '.join(comps)})"
            log.info("target %d unreachable: %s", i, exc)
        if progress:
            progress(i + 1, m)
    reachable = np.all(np.isfinite(q_act), axis=1)
    return Compensation(
        q_act, reachable, tuple(sorted(reasons)), reasons, tuple(calibrated.actuated), comps
    )
