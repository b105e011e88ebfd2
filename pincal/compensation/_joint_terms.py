"""Commands that include the joint terms: the deflection at the target's load, undone.

A calibration with joint terms (compliance under load, gain, harmonics; see
:mod:`pincal.model._joint_terms`) says that a command ``u`` moves the joints to
``q = u + B(u) θ``. Compensation first solves the calibrated geometry's inverse
kinematics for the joint values ``q*`` that reach the target, then the command that
produces them: ``u = q* − B(u) θ``, by fixed-point iteration from ``u = q*`` (the
terms are small and smooth, so it contracts fast; it stops at 1e-12 rad or m).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pincal.errors import ConvergenceError, ParameterError
from pincal.model import Mechanism, ParameterSet, joint_term_basis, parameters

__all__ = ["JointTermCorrection"]

_TOL = 1e-12  # [rad, m]
_MAX_ITER = 50


@dataclass(frozen=True)
class JointTermCorrection:
    """The identified joint terms of a calibration, as a map from commands to joints.

    Attributes:
        nominal: the mechanism the terms' basis is evaluated on (the identification's
            start model: a compliance's load comes from its inertias, payload included).
        params: the joint-term parameters (no geometric ones).
        values: (n,) their identified values [their SI units].
    """

    nominal: Mechanism
    params: ParameterSet
    values: np.ndarray

    @classmethod
    def of(
        cls, nominal: Mechanism, params: ParameterSet, values: np.ndarray
    ) -> JointTermCorrection:
        """The joint-term part of an identification's ``params`` and ``values`` (n,).

        Raises:
            ParameterError: ``values`` not of the size of ``params``.
        """
        values = np.asarray(values, dtype=float)
        if values.shape != (len(params),):
            raise ParameterError(f"values must have shape ({len(params)},), got {values.shape}")
        k = params.joint_terms
        return cls(nominal, params.subset(k), values[k].copy())

    @classmethod
    def from_names(
        cls, nominal: Mechanism, names: Sequence[str], values: np.ndarray
    ) -> JointTermCorrection:
        """From a result's parameter ``names`` and ``values`` (SI), e.g. read from a file.

        Raises:
            ParameterError, UnknownNameError: a name ``nominal`` does not have.
        """
        return cls.of(nominal, parameters(nominal, list(names)), values)

    def lines(self) -> list[str]:
        """One line per term: name, value and unit (SI; for reports)."""
        return [
            f"{name} = {v:+.4g} {unit}"
            for name, v, unit in zip(self.params.names, self.values, self.params.units, strict=True)
        ]

    def __bool__(self) -> bool:
        return bool(self.values.size)

    def deflection(self, commands: np.ndarray) -> np.ndarray:
        """Joint changes ``δq = B(u) θ`` (m, n_act) at commands ``u`` (m, n_act) [rad, m]."""
        u = np.atleast_2d(np.asarray(commands, dtype=float))
        if not self:
            return np.zeros_like(u)
        return joint_term_basis(self.nominal, self.params, u) @ self.values

    def commands(self, joints: np.ndarray) -> np.ndarray:
        """Commands (m, n_act) that move the joints to ``joints`` (m, n_act) [rad, m].

        Raises:
            ConvergenceError: the iteration does not settle (terms too large to invert).
        """
        q = np.atleast_2d(np.asarray(joints, dtype=float))
        u = q.copy()
        for _ in range(_MAX_ITER):
            new = q - self.deflection(u)
            step = float(np.max(np.abs(new - u), initial=0.0))
            u = new
            if step < _TOL:
                return u
        raise ConvergenceError(
            f"the command undoing the joint terms did not settle in {_MAX_ITER} steps (last "
            f"step {step:.3g}); the identified terms are too large for a small-deflection model"
        )
