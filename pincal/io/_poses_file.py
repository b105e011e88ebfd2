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

A target file may give only the components a machine controls (e.g. ``x,z,ry`` for a
3-DOF machine): the absent ones read as 0 and are listed as not given
(:attr:`PoseFile.components`). A rotation-vector subset is exact only for rotations
about one axis (what a machine controlling one rotation reaches).

Optionally the file carries the actuator values of each pose (``pincal poses`` writes
them): a header line ``# actuated: leg1 leg2 …`` names those columns, each titled
``name [unit]`` (``m``/``mm``/``um`` or ``rad``/``mrad``/``urad``/``deg``; SI without).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from pincal._yaml import shown
from pincal.errors import ColumnError, MeasurementError, MeasurementFormatError
from pincal.io._csv import (
    actuator_columns,
    fmt,
    header_value,
    header_words,
    parse_column,
    parse_numbers,
    split_file,
    write_csv,
)
from pincal.io._names import quote_words
from pincal.io._units import ANGLE_UNITS, LENGTH_UNITS, actuator_write_factors, unit_factor

__all__ = ["PoseFile", "read_pose_file", "read_poses", "write_poses"]

_ROTATION_COLUMNS = {"rotvec": ["rx", "ry", "rz"], "rpy": ["roll", "pitch", "yaw"]}


@dataclass(frozen=True, eq=False)
class PoseFile:
    """What :func:`read_pose_file` found.

    Attributes:
        poses: one world-frame ``pin.SE3`` per row [m] (absent components are 0).
        components: the components the file gives (subset of x y z rx ry rz, in that
            order; for ``rpy`` files the rotation is given whole or not at all).
        actuated: actuator column names (empty without a ``# actuated:`` header).
        q_act: (m, n_act) actuator values [m, rad], or None.
    """

    poses: list[pin.SE3]
    components: tuple[str, ...]
    actuated: tuple[str, ...] = ()
    q_act: np.ndarray | None = None


def _actuator_factors(units: list[str | None], joints: list[str], name: str) -> np.ndarray:
    factors = []
    for joint, unit in zip(joints, units, strict=True):
        if unit is None:
            factors.append(1.0)
        elif unit in LENGTH_UNITS:
            factors.append(LENGTH_UNITS[unit])
        elif unit in ANGLE_UNITS:
            factors.append(ANGLE_UNITS[unit])
        else:
            raise MeasurementFormatError(
                f"{name}: unit {shown(unit)} of actuator column {shown(joint)} unknown; use "
                f"{', '.join(LENGTH_UNITS)} or {', '.join(ANGLE_UNITS)}"
            )
    return np.array(factors)


def read_pose_file(path: str | Path) -> PoseFile:
    """Target poses (and optional actuator values) of a pose file (see the module doc).

    Args:
        path: the pose file.

    Returns:
        The :class:`PoseFile` [SI].

    Raises:
        MeasurementFormatError: bad header, unit or orientation, or no data rows.
        ColumnError: no pose column, or columns that are neither pose nor declared
            actuator columns.
        BadValueError, NonFiniteValueError: a cell that is not a finite number.
    """
    name = Path(path).name
    header, columns, rows = split_file(path, "poses")
    lf = unit_factor(LENGTH_UNITS, header_value(header, "length_unit", None, name), "length", name)
    af = unit_factor(ANGLE_UNITS, header_value(header, "angle_unit", "rad", name), "angle", name)
    orient = header_value(header, "orientation", "rotvec", name)
    if orient not in _ROTATION_COLUMNS:
        raise MeasurementFormatError(f"{name}: orientation {shown(orient)}; use rotvec or rpy")
    actuated = header_words(header, "actuated", name)
    want = ["x", "y", "z", *_ROTATION_COLUMNS[orient]]
    parsed = [parse_column(c) for c in columns]
    names = [p[0] for p in parsed]
    given = [c for c in want if c in names]
    extra = [c for c in names if c not in want and c not in actuated]
    missing_act = [a for a in actuated if a not in names]
    rot_given = [c for c in given if c in _ROTATION_COLUMNS[orient]]
    if not given or extra or missing_act or (orient == "rpy" and len(rot_given) not in (0, 3)):
        raise ColumnError(
            f"{name}: pose columns are {want} (all, or the components the machine controls"
            f"{'; roll pitch yaw together' if orient == 'rpy' else ''}) plus the actuator "
            f"columns named by '# actuated:'; not understood {shown(extra)}, missing actuator "
            f"columns {missing_act}",
            missing_act,
            extra,
        )
    data = parse_numbers(rows, columns, name)
    if data.shape[0] == 0:
        raise MeasurementFormatError(f"{name}: no data rows")
    full = np.zeros((data.shape[0], 6))
    for k, c in enumerate(want):
        if c in names:
            full[:, k] = data[:, names.index(c)]
    poses = []
    for row in full:
        a = row[3:] / af
        R = pin.exp3(a) if orient == "rotvec" else pin.rpy.rpyToMatrix(*a)
        poses.append(pin.SE3(R, row[:3] / lf))
    comp_names = ("x", "y", "z", "rx", "ry", "rz")
    comps = tuple(comp_names[want.index(c)] for c in given)
    q_act = None
    if actuated:
        idx = [names.index(a) for a in actuated]
        q_act = data[:, idx] / _actuator_factors([parsed[k][1] for k in idx], actuated, name)
    return PoseFile(poses, comps, tuple(actuated), q_act)


def read_poses(path: str | Path) -> list[pin.SE3]:
    """Target poses of the measured frame in the world frame (see the module doc).

    Args:
        path: the pose file.

    Returns:
        One ``pin.SE3`` per data row [m] (see :func:`read_pose_file` for the components
        and actuator values).

    Raises:
        MeasurementFormatError: bad header, unit or orientation, or no data rows.
        ColumnError: missing or unknown columns.
        BadValueError, NonFiniteValueError: a cell that is not a finite number.
    """
    return read_pose_file(path).poses


def write_poses(
    path: str | Path,
    poses: Sequence[pin.SE3],
    *,
    length_unit: str = "mm",
    angle_unit: str = "mrad",
    orientation: str = "rotvec",
    actuated: Sequence[str] = (),
    q_act: np.ndarray | None = None,
    actuator_units: Sequence[str] | None = None,
) -> Path:
    """Write target poses (world frame) atomically, optionally with their actuator values.

    Args:
        path: output file.
        poses: the poses [m].
        length_unit: unit of the file's position columns, one of ``"m"``, ``"mm"``,
            ``"um"``.
        angle_unit: unit of the file's orientation columns, one of ``"rad"``,
            ``"mrad"``, ``"urad"``, ``"deg"``.
        orientation: ``"rotvec"`` or ``"rpy"``.
        actuated: actuator column names (n_act,) when ``q_act`` is given.
        q_act: (m, n_act) actuator values [m, rad] or None.
        actuator_units: unit per actuator column (written as ``name [unit]``); SI if None.

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
    header = [
        f"length_unit: {length_unit}",
        f"angle_unit: {angle_unit}",
        f"orientation: {orientation}",
    ]
    act_cols: list[str] = []
    if q_act is not None:
        q_act = np.atleast_2d(np.asarray(q_act, dtype=float))
        if q_act.shape != (len(poses), len(actuated)):
            raise MeasurementError(
                f"q_act has shape {q_act.shape}; expected ({len(poses)}, {len(actuated)})"
            )
        header.append(f"actuated: {quote_words(actuated, 'actuated joint')}")
        act_cols = actuator_columns(actuated, actuator_units)
        afac = actuator_write_factors(actuator_units, len(actuated))
    rows = []
    for i, T in enumerate(poses):
        a = pin.log3(T.rotation) if orientation == "rotvec" else pin.rpy.matrixToRpy(T.rotation)
        row = [*(T.translation * lf), *(np.asarray(a) * af)]
        if q_act is not None:
            row += list(q_act[i] * afac)
        rows.append([fmt(v) for v in row])
    return write_csv(
        path, "poses", header, ["x", "y", "z", *_ROTATION_COLUMNS[orientation], *act_cols], rows
    )
