"""Orientation columns of a 6-D marker body: declared conventions and rotation matrices.

A motion-capture *marker body* (a rigid set of markers) is reported as a position and
an orientation of the body in the instrument frame. The orientation is given by
columns in a declared convention, ``NAME-UNIT`` or a quaternion order:

=============  ======================================================================
``rpy-deg``    roll, pitch, yaw [deg]: R = Rz(yaw) · Ry(pitch) · Rx(roll) (fixed axes
``rpy-rad``    x, then y, then z; the URDF ``rpy`` convention) [rad]
``xyz-deg``    Euler angles a, b, c about moving axes x, y', z'': R = Rx(a) · Ry(b) ·
``xyz-rad``    Rz(c) [deg | rad]
``rotvec-deg`` rotation vector (axis × angle) [deg | rad]: R = exp([v]×)
``rotvec-rad``
``quat-wxyz``  unit quaternion, scalar first (w x y z) [1]
``quat-xyzw``  unit quaternion, scalar last (x y z w) [1]
=============  ======================================================================

:func:`rotation_matrices` turns (m, k) column values into (m, 3, 3) rotation matrices;
:func:`orientation_problems` names the values that cannot be of the declared
convention (a quaternion not of unit norm, an angle beyond a turn).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from pincal.errors import MeasurementError

__all__ = [
    "ORIENTATIONS",
    "QUATERNION_TOLERANCE",
    "check_orientation",
    "orientation_problems",
    "rotation_matrices",
]

#: the declared conventions: name → number of columns
ORIENTATIONS = {
    "rpy-deg": 3,
    "rpy-rad": 3,
    "xyz-deg": 3,
    "xyz-rad": 3,
    "rotvec-deg": 3,
    "rotvec-rad": 3,
    "quat-wxyz": 4,
    "quat-xyzw": 4,
}
#: largest | ‖q‖ − 1 | of a quaternion read (exports round to 4–6 digits: ~1e-5)
QUATERNION_TOLERANCE = 1e-3
#: largest |angle| of an angle column, in turns (an unwrapped export may pass π)
_TURN_LIMIT = 1.0 + 1e-9


def check_orientation(convention: str, columns: tuple[str, ...]) -> None:
    """Raise MeasurementError unless ``convention`` is known and ``columns`` fit it."""
    if convention not in ORIENTATIONS:
        raise MeasurementError(
            f"orientation convention {convention!r} is not known; use one of "
            f"{', '.join(ORIENTATIONS)} (rpy: R = Rz(yaw)·Ry(pitch)·Rx(roll))"
        )
    n = ORIENTATIONS[convention]
    if len(columns) != n or len(set(columns)) != n:
        raise MeasurementError(
            f"orientation {convention} needs {n} distinct columns, got {list(columns)}"
        )


def _scale(convention: str) -> float:
    """Factor taking the columns' angle unit to radians (1 for quaternions)."""
    return np.pi / 180.0 if convention.endswith("-deg") else 1.0


def orientation_problems(values: np.ndarray, convention: str) -> list[tuple[int, int, str]]:
    """Values that cannot be of ``convention``: (row, column, why) for each, at most one per row.

    Args:
        values: (m, k) finite column values in the declared unit.
        convention: one of :data:`ORIENTATIONS`.

    Returns:
        Quaternions whose norm is off 1 by more than :data:`QUATERNION_TOLERANCE`
        (column -1: the row's quaternion); angles beyond one turn (360° or 2π rad).
    """
    out: list[tuple[int, int, str]] = []
    if convention.startswith("quat"):
        norm = np.linalg.norm(values, axis=1)
        for i in np.flatnonzero(np.abs(norm - 1.0) > QUATERNION_TOLERANCE):
            out.append((int(i), -1, f"quaternion norm {norm[i]:.6g}, not 1 within "
                                    f"{QUATERNION_TOLERANCE:g}"))  # fmt: skip
        return out
    turn = 360.0 if convention.endswith("-deg") else 2 * np.pi
    unit = "°" if convention.endswith("-deg") else " rad"
    if convention.startswith("rotvec"):
        size = np.linalg.norm(values, axis=1)
        big = np.flatnonzero(size > turn * _TURN_LIMIT)
        return [(int(i), -1, f"rotation of {size[i]:.6g}{unit}, beyond a turn") for i in big]
    for i, k in zip(*np.nonzero(np.abs(values) > turn * _TURN_LIMIT), strict=True):
        if not any(r == i for r, _, _ in out):
            out.append((int(i), int(k), f"{values[i, k]:.6g}{unit} is beyond a turn"))
    return out


def rotation_matrices(values: np.ndarray, convention: str) -> np.ndarray:
    """(m, 3, 3) rotation matrices of (m, k) orientation values in ``convention``.

    Quaternions are normalised (check them first with :func:`orientation_problems`).

    Raises:
        MeasurementError: unknown convention or wrong number of columns.
    """
    values = np.asarray(values, dtype=float)
    n = ORIENTATIONS.get(convention)
    if n is None or values.ndim != 2 or values.shape[1] != n:
        raise MeasurementError(
            f"orientation {convention!r}: expected (m, {n}) values, got {values.shape}"
        )
    out = np.empty((len(values), 3, 3))
    if convention.startswith("quat"):
        q = values if convention == "quat-wxyz" else values[:, [3, 0, 1, 2]]
        q = q / np.linalg.norm(q, axis=1, keepdims=True)
        for i, (w, x, y, z) in enumerate(q):
            out[i] = pin.Quaternion(w, x, y, z).toRotationMatrix()
        return out
    a = values * _scale(convention)
    for i, v in enumerate(a):
        if convention.startswith("rpy"):
            out[i] = pin.rpy.rpyToMatrix(*v)  # Rz(yaw) Ry(pitch) Rx(roll)
        elif convention.startswith("xyz"):
            out[i] = _rx(v[0]) @ _ry(v[1]) @ _rz(v[2])
        else:
            out[i] = pin.exp3(v)
    return out


def _rx(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _ry(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _rz(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
