from __future__ import annotations

import numpy as np
import pytest

from pincal.measure import Distance, Plane, Point, Sphere
from pincal.model import sample_actuators


@pytest.fixture(scope="session")
def stewart_rows80(stewart) -> np.ndarray:
    return sample_actuators(stewart, 80, np.random.default_rng(21))


@pytest.fixture(scope="session")
def stewart_tool80(stewart, stewart_rows80) -> np.ndarray:
    qs = stewart.configurations(stewart_rows80)
    return np.array([stewart.frame_placement(q).translation for q in qs])


def setups(P: np.ndarray) -> dict:
    """One instrument of every kind near tool points P, with true parameters and plane ids."""
    c = P.mean(axis=0)
    ids = np.arange(len(P)) % 2
    return {
        "distance": (
            Distance(1e-6),
            np.r_[c + np.array([0.01, 0.02, -0.15]), 1e-3],
            None,
        ),
        "sphere": (Sphere(1e-6, radius=0.02), c + np.array([0.0, 0.01, -0.1]), None),
        "plane": (
            Plane(1e-6, normals=((0, 0, 1), (1, 0, 0.1))),
            np.array([1e-3, -2e-3, 0.3, 2e-3, 1e-3, 0.05]),
            ids,
        ),
        "point": (Point(1e-6, direction=(0.1, 0, 1)), np.array([0.03]), None),
    }
