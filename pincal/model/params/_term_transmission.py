"""Transmission errors: joint gain (encoder scale) and gear-eccentricity harmonics.

* gain: ``δq = g · q`` (dimensionless, unit ``1``);
* harmonics: ``δq = s1 sin q + c1 cos q + s2 sin 2q + c2 cos 2q`` [rad], revolute
  joints only (first and second harmonics of the joint angle).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, ClassVar

import numpy as np

from pincal.errors import ParameterError
from pincal.model.params._joint_terms import JointTerm, register_term

if TYPE_CHECKING:
    from pincal.model._mechanism import Mechanism

__all__ = ["Gain", "Harmonics"]


class Gain(JointTerm):
    """Joint gain: ``δq_i = g_i · q_i`` (1σ prior 1e-3, i.e. 0.1 %)."""

    kind: ClassVar[str] = "gain"
    dofs: ClassVar[tuple[str, ...]] = ("gain",)
    prior: ClassVar[float] = 1e-3

    def unit(self, joint_type: str) -> str:
        return "1"

    def basis(self, mech: Mechanism, q_act: np.ndarray) -> np.ndarray:
        return np.asarray(q_act, dtype=float)[:, :, None].copy()


class Harmonics(JointTerm):
    """First and second harmonics of a revolute joint angle (1σ prior 1 mrad)."""

    kind: ClassVar[str] = "harmonics"
    dofs: ClassVar[tuple[str, ...]] = ("sin1", "cos1", "sin2", "cos2")
    prior: ClassVar[float] = 1e-3

    def unit(self, joint_type: str) -> str:
        return "rad"

    def check(self, mech: Mechanism, joint: str) -> None:
        super().check(mech, joint)
        kind = mech.tree.joints[joint].type
        if kind not in ("revolute", "continuous"):
            raise ParameterError(
                f"harmonic terms are for revolute joints; {joint!r} is {kind} (use 'gain')"
            )

    def basis(self, mech: Mechanism, q_act: np.ndarray) -> np.ndarray:
        q = np.asarray(q_act, dtype=float)
        return np.stack([np.sin(q), np.cos(q), np.sin(2 * q), np.cos(2 * q)], axis=2)


register_term(Gain())
register_term(Harmonics())
