"""The poses ``pincal view`` draws, and the calibration's change of prediction at each.

:func:`view_poses` reads a pose, command or measurement file and/or draws random
workspace poses, and closes them into configurations; :func:`prediction_changes` gives,
at each of them, the measured frame's position predicted by the nominal and by the
calibrated model (the ends of the arrows the view draws). Nothing is drawn here.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pincal.errors import ConvergenceError
from pincal.io import read_pose_rows
from pincal.model import Mechanism, sample_actuators

__all__ = ["PredictionChanges", "ViewPoses", "prediction_changes", "view_poses"]


@dataclass(frozen=True)
class ViewPoses:
    """The poses :func:`view_poses` found.

    Attributes:
        rows: (m, n_act) actuator values [m, rad].
        configurations: (m, nq) closed configurations of the mechanism.
    """

    rows: np.ndarray
    configurations: np.ndarray

    def __len__(self) -> int:
        """The number of poses m."""
        return len(self.rows)


@dataclass(frozen=True)
class PredictionChanges:
    """The measured frame's position by the nominal and the calibrated model, per pose.

    Attributes:
        nominal: (m, 3) positions the nominal model predicts, world frame [m].
        calibrated: (m, 3) positions the calibrated model predicts, world frame [m]
            (NaN at a pose the calibrated machine cannot reach).
        largest_mm: the largest distance between the two at a pose [mm] (reached poses).
        unreachable: indices of the poses whose commands the calibrated model cannot
            close on home's assembly branch (beyond the calibrated machine's workspace).
    """

    nominal: np.ndarray
    calibrated: np.ndarray
    largest_mm: float
    unreachable: tuple[int, ...] = ()


def view_poses(
    mech: Mechanism,
    poses_file: str | Path | None,
    n_random: int | None,
    seed: int,
    max_rows: int | None = None,
) -> ViewPoses:
    """The file's poses followed by ``n_random`` random ones (5 without a file or a count).

    Args:
        mech: the mechanism.
        poses_file: a pose, command or measurement file, or a CSV naming the actuated
            joints (:func:`pincal.io.read_pose_rows`); None: random poses only.
        n_random: random workspace poses drawn (:func:`pincal.model.sample_actuators`).
        seed: seed of the random poses.
        max_rows: refuse a file with more rows (None: no limit).

    Raises:
        MeasurementError, UnreachablePoseError, ActuatorRangeError: reading the file.
    """
    if poses_file is not None:
        rows = read_pose_rows(poses_file, mech, max_rows)
        if n_random:
            rows = np.vstack([rows, sample_actuators(mech, n_random, np.random.default_rng(seed))])
    else:
        rows = sample_actuators(mech, n_random or 5, np.random.default_rng(seed))
    return ViewPoses(rows, mech.configurations(rows))


def prediction_changes(
    nominal: Mechanism, calibrated: Mechanism, poses: ViewPoses
) -> PredictionChanges:
    """The measured frame's position at each pose by ``nominal`` and by ``calibrated``.

    Both are evaluated at the actuator rows and configurations of ``poses`` (found on
    ``nominal``); the two mechanisms have the same actuators. A pose near the workspace's
    edge may be out of the calibrated machine's reach: it is listed in ``unreachable``.
    """
    starts, ends, lengths, unreachable = [], [], [], []
    for k, row in enumerate(poses.rows):
        q = poses.configurations[k]
        p_nominal = np.array(nominal.forward(row, q).translation)
        try:
            p_calibrated = np.array(calibrated.forward(row, q).translation)
            lengths.append(float(np.linalg.norm(p_calibrated - p_nominal)) * 1e3)
        except ConvergenceError:
            p_calibrated = np.full(3, np.nan)
            unreachable.append(k)
        starts.append(p_nominal)
        ends.append(p_calibrated)
    return PredictionChanges(
        np.array(starts).reshape(-1, 3),
        np.array(ends).reshape(-1, 3),
        max(lengths, default=0.0),
        tuple(unreachable),
    )
