"""Actuator rows from any pincal file that names or implies them (for viewing)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pincal._yaml import shown
from pincal.errors import MeasurementError, UnreachablePoseError
from pincal.io._commands_file import read_actuator_rows, read_commands
from pincal.io._csv import file_kind
from pincal.io._measurement_file import read_measurements
from pincal.io._poses_file import read_pose_file
from pincal.io._units import check_actuator_ranges
from pincal.model import Mechanism

__all__ = ["read_pose_rows"]


def read_pose_rows(path: str | Path, mech: Mechanism, max_rows: int | None = None) -> np.ndarray:
    """Actuator rows (m, n_act) [m, rad] of ``mech`` read from a file.

    The file is a pose, command or measurement file, or any CSV whose header names the
    actuated joints. A pose file without actuator columns is solved with ``mech``'s
    inverse kinematics.

    Args:
        path: the file.
        mech: the model whose actuated joints the rows are for.
        max_rows: refuse files with more rows than this (None: no limit).

    Raises:
        MeasurementError: unreadable or malformed file, missing actuator columns, too
            many rows.
        UnreachablePoseError: a pose of a pose file that ``mech`` cannot reach.
        ActuatorRangeError: an actuator value far outside its joint's URDF limits.
    """
    path = Path(path)
    kind = file_kind(path)
    if kind == "poses":
        pf = read_pose_file(path)
        if pf.q_act is not None:
            missing = [j for j in mech.actuated if j not in pf.actuated]
            if missing:
                raise MeasurementError(
                    f"{path.name}: actuator columns {shown(list(pf.actuated))} lack {missing} of "
                    f"model {mech.name!r}"
                )
            rows = pf.q_act[:, [pf.actuated.index(j) for j in mech.actuated]]
            check_actuator_ranges(mech, rows, path.name)
        else:
            out, bad = [], []
            for i, T in enumerate(pf.poses):
                try:
                    out.append(mech.inverse(T))
                except UnreachablePoseError:
                    bad.append(i)
            if bad:
                raise UnreachablePoseError(
                    f"{path.name}: poses {bad} unreachable by {mech.name!r}", residual=0.0
                )
            rows = np.array(out)
    elif kind == "commands":
        rows = read_commands(path, mech)[1]
    elif kind == "measurements":
        rows = read_measurements(path, mech).q_act
    elif kind is not None:
        raise MeasurementError(
            f"{path.name} is a pincal {shown(kind)} file; give a poses, commands or "
            "measurements file"
        )
    else:
        rows = read_actuator_rows(path, mech.actuated, max_rows)
        check_actuator_ranges(mech, rows, path.name)
        return rows
    if max_rows is not None and len(rows) > max_rows:
        raise MeasurementError(
            f"poses file {str(path)!r} has {len(rows)} poses; at most {max_rows}"
        )
    return np.asarray(rows, dtype=float)
