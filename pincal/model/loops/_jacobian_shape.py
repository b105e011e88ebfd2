"""Pinocchio's frame Jacobians as (6, nv) matrices, whatever nv.

Pinocchio hands a one-velocity model's (6, 1) Jacobian to Python as a (6,) vector;
indexing it as a matrix (``J[rows, cols]``) then fails with an ``IndexError``. A
marker on the first link of a chain (one unlocked joint) builds such a model.
"""

from __future__ import annotations

import numpy as np

__all__ = ["six_by_nv"]


def six_by_nv(J: np.ndarray) -> np.ndarray:
    """``J`` (6, nv) or (6,) as a (6, nv) matrix (a view when possible)."""
    return np.reshape(J, (6, -1))
