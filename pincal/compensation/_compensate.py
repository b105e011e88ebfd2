"""Compensation: actuator commands that bring the *calibrated* model to target poses.

Compensation is inverse kinematics with the calibrated model: the commands for
which the identified machine (not the nominal one) reaches each target. Each target's
inverse kinematics starts from a *start command*: the target's own nominal command when
one is given (``starts``, e.g. the actuator columns of a pose file), otherwise the
solved command of the nearest target solved before it (home for the first). A solution
on another branch than its start (see :mod:`pincal.compensation._branch`) is refused
unless ``allow_branch_change``; either way it is reported.

Only the components the machine controls are imposed: by default the model's
measured components (``mech.measured_components``, e.g. ``x z ry`` for the 3-DOF
wedge), or the ``components`` given. A machine of mobility n cannot meet more than
n independent components, so asking for more is refused with the reason.

A calibration with joint terms (compliance under load, gain, harmonics) passes them as
``joint_terms`` (:class:`~pincal.compensation._joint_terms.JointTermCorrection`): the
commands then include the deflection at each target's load (the joint values the
geometry needs, minus what the terms add at those commands).
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from pincal.compensation._branch import actuator_units, branch_change, unwrapped
from pincal.compensation._joint_terms import JointTermCorrection
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
        starts: (m, n_act) start command of each target's inverse kinematics [m, rad].
        start_sources: per target, where its start came from (``"nominal"``,
            ``"target j"`` — the nearest solved one — or ``"home"``).
        branch_changes: {index: why} of solutions on another branch than their start
            (refused, i.e. unreachable, unless allowed).
        units: ``"rad"`` or ``"m"`` per actuator.
        deflection: (m, n_act) joint change the joint terms add at each command (the
            commands include its opposite) [rad, m]; None without joint terms.
    """

    q_act: np.ndarray
    reachable: np.ndarray
    unreachable: tuple[int, ...]
    reasons: dict[int, str]
    actuated: tuple[str, ...]
    components: tuple[str, ...] = COMPONENTS
    starts: np.ndarray | None = None
    start_sources: tuple[str, ...] = ()
    branch_changes: dict[int, str] | None = None
    units: tuple[str, ...] = ()
    deflection: np.ndarray | None = None

    @property
    def commands(self) -> np.ndarray:
        """(r, n_act) the rows of the reachable targets only."""
        return self.q_act[self.reachable]

    def largest_step(self, unit: str) -> tuple[float, int, int] | None:
        """Largest |q_act − start| over reachable targets and actuators of ``unit``.

        Args:
            unit: ``"rad"`` (revolute actuators) or ``"m"`` (prismatic ones).

        Returns:
            (|Δq| [unit], target index, actuator index), or None when no actuator has
            that unit or no target was reached.
        """
        cols = np.array([k for k, u in enumerate(self.units) if u == unit], dtype=int)
        rows = np.flatnonzero(self.reachable)
        if self.starts is None or not cols.size or not rows.size:
            return None
        dq = np.abs(self.q_act[np.ix_(rows, cols)] - self.starts[np.ix_(rows, cols)])
        i, k = np.unravel_index(int(np.argmax(dq)), dq.shape)
        return float(dq[i, k]), int(rows[i]), int(cols[k])


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


def _nearest(T: pin.SE3, solved: list[tuple[int, pin.SE3]]) -> int | None:
    """Index of the solved target nearest to ``T`` (position + 0.1 m per rad of rotation)."""
    if not solved:
        return None
    d = [
        np.linalg.norm(T.translation - S.translation)
        + 0.1 * np.linalg.norm(pin.log3(S.rotation.T @ T.rotation))
        for _, S in solved
    ]
    return solved[int(np.argmin(d))][0]


def _check_starts(starts: ArrayLike | None, m: int, n: int) -> np.ndarray | None:
    if starts is None:
        return None
    arr = np.asarray(starts, dtype=float)
    if arr.shape != (m, n):
        raise MeasurementError(
            f"start commands must be (targets, actuators) = ({m}, {n}), got {arr.shape}"
        )
    return arr


def compensate(
    calibrated: Mechanism,
    targets: Sequence[pin.SE3] | np.ndarray,
    check_limits: bool = True,
    progress: Callable[[int, int], None] | None = None,
    components: Sequence[str] | str | None = None,
    *,
    starts: ArrayLike | None = None,
    allow_branch_change: bool = False,
    joint_terms: JointTermCorrection | None = None,
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
        starts: (m, n_act) nominal command of each target [m, rad] (rows of NaN: none),
            the start of its inverse kinematics; without one a target starts from the
            solved command of the nearest target solved before it (home for the first).
        allow_branch_change: keep solutions on another branch than their start
            (reported in ``branch_changes``); by default they are refused.
        joint_terms: the calibration's joint terms; the commands then move the joints
            to the inverse kinematics' values (deflection at the target's load included).

    Returns:
        A :class:`Compensation`; unreachable targets (and refused branch changes) are
        reported by index with the reason, not raised.

    Raises:
        MeasurementError: targets that are neither ``pin.SE3`` poses nor an (m, 6)
            array of finite numbers, bad ``components`` or ``starts`` of the wrong shape.
        MobilityError: more components than the machine's mobility.
    """
    poses = _as_poses(targets)
    comps = compensation_components(calibrated, components)
    solver = _solver(calibrated, comps)
    m, n = len(poses), calibrated.n_actuated
    nominal = _check_starts(starts, m, n)
    units = actuator_units(calibrated)
    lo, hi = np.asarray(calibrated.actuator_limits, dtype=float).T
    q_act = np.full((m, n), np.nan)
    start_rows = np.full((m, n), np.nan)
    sources: list[str] = []
    reasons: dict[int, str] = {}
    changes: dict[int, str] = {}
    solved: list[tuple[int, pin.SE3]] = []
    full: dict[int, np.ndarray] = {}
    for i, T in enumerate(poses):
        guess, source = None, "home"
        if nominal is not None and np.all(np.isfinite(nominal[i])):
            start_rows[i], source = nominal[i], "nominal"
            try:
                guess = solver.configuration(nominal[i])
            except ConvergenceError:
                guess = None  # the closure of the start failed: Newton starts from home
        else:
            j = _nearest(T, solved)
            if j is not None:
                guess, source = full[j], f"target {j}"
                start_rows[i] = q_act[j]
        if source == "home":
            start_rows[i] = solver.actuators_of(solver.q_home)
        sources.append(source)
        try:
            q = solver.inverse_configuration(T, guess)
            if joint_terms:
                q = joint_terms.solve(solver, T, q)
            joints = unwrapped(solver, solver.actuators_of(q), start_rows[i])
            row = joint_terms.commands(joints[None])[0] if joint_terms else joints
            if check_limits:
                out = np.nonzero((row < lo - 1e-12) | (row > hi + 1e-12))[0]
                if out.size:
                    k = int(out[0])
                    raise ConvergenceError(
                        f"needs {calibrated.actuated[k]} = {row[k]:.6g}, outside "
                        f"[{lo[k]:.6g}, {hi[k]:.6g}]"
                    )
            why = branch_change(
                solver, start_rows[i], joints, guess, q, units, own_start=source == "nominal"
            )
            if why:
                changes[i] = why
                if not allow_branch_change:
                    raise ConvergenceError(
                        f"the solution is on another branch than its {source} start: {why}; "
                        "allow it with --allow-branch-change (allow_branch_change=True)"
                    )
            q_act[i] = row
            full[i] = q
            solved.append((i, T))
        except ConvergenceError as exc:
            reasons[i] = f"{exc} (imposing {' '.join(comps)})"
            log.info("target %d unreachable: %s", i, exc)
        if progress:
            progress(i + 1, m)
    reachable = np.all(np.isfinite(q_act), axis=1)
    deflection = None
    if joint_terms:
        deflection = np.full_like(q_act, np.nan)
        deflection[reachable] = joint_terms.deflection(q_act[reachable])
    return Compensation(
        q_act, reachable, tuple(sorted(reasons)), reasons, tuple(calibrated.actuated), comps,
        start_rows, tuple(sources), changes, units, deflection,
    )  # fmt: skip
