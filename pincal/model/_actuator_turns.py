"""Differences of actuator values, a continuous joint's taken as one angle.

A continuous (unbounded revolute) joint's configuration holds (cos θ, sin θ), read back
in (−π, π]: the same angle can read 2π apart. :func:`actuator_difference` takes such a
joint's difference within π; every other actuator's is the plain difference.
"""

from __future__ import annotations

import numpy as np

from pincal.model._mechanism import Mechanism

__all__ = ["actuator_difference"]


def actuator_difference(mech: Mechanism, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a − b`` (..., n_act) [m, rad], a continuous actuator's wrapped into (−π, π]."""
    d = np.asarray(a, dtype=float) - np.asarray(b, dtype=float)
    endless = np.array([mech.tree.joints[j].type == "continuous" for j in mech.actuated])
    return np.where(endless, np.angle(np.exp(1j * d)), d)
