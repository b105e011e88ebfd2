"""Pose files: target poses of the measured frame in the world frame.

::

    # pincal poses 1
    # length_unit: mm                 m | mm | um
    # angle_unit: mrad                rad | mrad | urad | deg
    # orientation: rotvec             rotvec | rpy
    x,y,z,rx,ry,rz

Columns ``x y z`` and ``rx ry rz`` (rotation vector, ``orientation: rotvec``) or
``roll pitch yaw`` (``orientation: rpy``, R = Rz(yaw)·Ry(pitch)·Rx(roll)). Used as
targets for compensation and as designed measurement poses.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pinocchio as pin

from pincal.errors import ColumnError, MeasurementError, MeasurementFormatError
from pincal.io._csv import fmt, header_value, parse_column, parse_numbers, split_file, write_csv
from pincal.io._units import ANGLE_UNITS, LENGTH_UNITS, unit_factor

__all__ = ["read_poses", "write_poses"]

_ROTATION_COLUMNS = {"rotvec": ["rx", "ry", "rz"], "rpy": ["roll", "pitch", "yaw"]}


def read_poses(path: str | Path) -> list[pin.SE3]:
    """Target poses of the measured frame in the world frame (see the module doc).

    Args:
        path: the pose file.

    Returns:
        One ``pin.SE3`` per data row [m].

    Raises:
        MeasurementFormatError: bad header, unit or orientation, or no data rows.
        ColumnError: missing or unknown columns.
        BadValueError, NonFiniteValueError: a cell that is not a finite number.
    """
    name = Path(path).name
    header, columns, rows = split_file(path, "poses")
    lf = unit_factor(LENGTH_UNITS, header_value(header, "length_unit", None, name), "length", name)
    af = unit_factor(ANGLE_UNITS, header_value(header, "angle_unit", "rad", name), "angle", name)
    orient = header_value(header, "orientation", "rotvec", name)
    if orient not in _ROTATION_COLUMNS:
        raise MeasurementFormatError(f"{name}: orientation {orient!r}; use rotvec or rpy")
    want = ["x", "y", "z", *_ROTATION_COLUMNS[orient]]
    names = [parse_column(c)[0] for c in columns]
    missing = [c for c in want if c not in names]
    extra = [c for c in names if c not in want]
    if missing or extra:
        raise ColumnError(
            f"{name}: pose columns must be {want}; missing {missing}, not understood {extra}",
            missing,
            extra,
        )
    data = parse_numbers(rows, columns, name)
    if data.shape[0] == 0:
        raise MeasurementFormatError(f"{name}: no data rows")
    data = data[:, [names.index(c) for c in want]]
    poses = []
    for row in data:
        a = row[3:] / af
        R = pin.exp3(a) if orient == "rotvec" else pin.rpy.rpyToMatrix(*a)
        poses.append(pin.SE3(R, row[:3] / lf))
    return poses


def write_poses(
    path: str | Path,
    poses: Sequence[pin.SE3],
    *,
    length_unit: str = "mm",
    angle_unit: str = "mrad",
    orientation: str = "rotvec",
) -> Path:
    """Write target poses (world frame) atomically.

    Args:
        path: output file.
        poses: the poses [m].
        length_unit, angle_unit: units of the file's columns.
        orientation: ``"rotvec"`` or ``"rpy"``.

    Returns:
        The written path.

    Raises:
        MeasurementFormatError: unknown unit.
        MeasurementError: unknown orientation.
    """
    lf = unit_factor(LENGTH_UNITS, length_unit, "length", "write_poses")
    af = unit_factor(ANGLE_UNITS, angle_unit, "angle", "write_poses")
    if orientation not in _ROTATION_COLUMNS:
        raise MeasurementError(f"orientation {orientation!r}; use rotvec or rpy")
    rows = []
    for T in poses:
        a = pin.log3(T.rotation) if orientation == "rotvec" else pin.rpy.matrixToRpy(T.rotation)
        rows.append([fmt(v) for v in [*(T.translation * lf), *(np.asarray(a) * af)]])
    return write_csv(
        path,
        "poses",
        [f"length_unit: {length_unit}", f"angle_unit: {angle_unit}", f"orientation: {orientation}"],
        ["x", "y", "z", *_ROTATION_COLUMNS[orientation]],
        rows,
    )
