"""Orientation conventions of marker bodies: every one gives back the rotation it encodes.

The column values are computed from random rotations by formulas independent of the
reader (Pinocchio's rpy and quaternion, log3; the xyz-Euler angles solved by hand from
the matrix), so a swapped order or a wrong sign fails.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from pincal.errors import MeasurementError
from pincal.measure import MarkerSetup, orientation_problems, rotation_matrices

ROT = [pin.exp3(v) for v in np.random.default_rng(3).uniform(-1.2, 1.2, (20, 3))]


def _xyz_euler(R: np.ndarray) -> np.ndarray:
    """(a, b, c) with R = Rx(a) Ry(b) Rz(c) (|b| < π/2)."""
    return np.array([np.arctan2(-R[1, 2], R[2, 2]), np.arcsin(R[0, 2]),
                     np.arctan2(-R[0, 1], R[0, 0])])  # fmt: skip


def _values(convention: str) -> np.ndarray:
    out = []
    for R in ROT:
        if convention.startswith("rpy"):
            v = pin.rpy.matrixToRpy(R)
        elif convention.startswith("xyz"):
            v = _xyz_euler(R)
        elif convention.startswith("rotvec"):
            v = pin.log3(R)
        else:
            x, y, z, w = pin.Quaternion(R).coeffs()
            v = np.array([w, x, y, z] if convention == "quat-wxyz" else [x, y, z, w])
        out.append(np.degrees(v) if convention.endswith("-deg") else v)
    return np.array(out)


@pytest.mark.parametrize("convention", ["rpy-deg", "rpy-rad", "xyz-deg", "xyz-rad",
                                        "rotvec-deg", "rotvec-rad", "quat-wxyz", "quat-xyzw"])
def test_each_convention_gives_back_its_rotations(convention):
    values = _values(convention)
    assert orientation_problems(values, convention) == []
    R = rotation_matrices(values, convention)
    assert np.allclose(R, np.array(ROT), atol=1e-12)


def test_rpy_is_fixed_axes_x_then_y_then_z():
    r, p, y = 0.3, -0.2, 0.6
    Rx, Ry, Rz = (pin.exp3(a * e) for a, e in zip((r, p, y), np.eye(3), strict=True))
    assert np.allclose(rotation_matrices(np.array([[r, p, y]]), "rpy-rad")[0], Rz @ Ry @ Rx)
    assert np.allclose(rotation_matrices(np.array([[r, p, y]]), "xyz-rad")[0], Rx @ Ry @ Rz)


def test_values_not_of_the_convention_are_named():
    q = np.array([[1.0, 0.0, 0.0, 0.0], [0.9, 0.1, 0.0, 0.0]])
    (bad,) = orientation_problems(q, "quat-wxyz")
    assert bad[0] == 1 and "norm" in bad[2]
    (bad,) = orientation_problems(np.array([[10.0, 20.0, 30.0]]), "rpy-rad")
    assert bad[:2] == (0, 0) and "beyond a turn" in bad[2]
    assert orientation_problems(np.array([[170.0, -90.0, 359.0]]), "rpy-deg") == []
    assert orientation_problems(np.array([[400.0, 0.0, 0.0]]), "rotvec-deg")


def test_the_setup_checks_its_orientation_declaration():
    with pytest.raises(MeasurementError, match="not known"):
        MarkerSetup("l", orientation_columns=("a", "b", "c"), orientation="zyx-deg")
    with pytest.raises(MeasurementError, match="needs 4 distinct columns"):
        MarkerSetup("l", orientation_columns=("a", "b", "c"), orientation="quat-wxyz")
    with pytest.raises(MeasurementError, match="together"):
        MarkerSetup("l", orientation_columns=("a", "b", "c"))
    with pytest.raises(MeasurementError, match="position and as orientation"):
        MarkerSetup("l", orientation_columns=("r", "p", "y"), orientation="rpy-deg")
    with pytest.raises(MeasurementError, match="one marker body"):
        MarkerSetup("l", more_columns=(("u", "v", "w"),), orientation_columns=("a", "b", "c"),
                    orientation="rpy-deg")  # fmt: skip
    s = MarkerSetup("l", orientation_columns=("a", "b", "c"), orientation="rpy-deg")
    assert MarkerSetup.from_dict(s.to_dict()) == s
    assert "orientation" not in MarkerSetup("l").to_dict()  # position-only records unchanged
