"""Commands that include the joint terms: the deflection at the target's load, undone.

A calibration with joint terms (compliance under load, gain, harmonics; see
:mod:`pincal.model.params._joint_terms`) says that a command ``u`` moves the joints to
``q = u + B(u) θ``. Compensation first solves the calibrated geometry's inverse
kinematics for the joint values ``q*`` that reach the target, then the command that
produces them: ``u = q* − B(u) θ``, by fixed-point iteration from ``u = q*`` (the
terms are small and smooth, so it contracts fast; it stops at 1e-12 rad or m).

A compliance (a load-dependent term) deflects the calibrated machine under its own loads
at the configuration it deflects to, as the identification models it
(:func:`pincal.model.deflected_joints`): forward, the fixed point ``q = u' + L(q) θ_L``
(``u'`` the command moved by the other terms); inverse, the load is known at the joints
to reach, ``u' = q* − L(q*) θ_L``.

A term that moves the measured frame instead of the joints (a link's thermal expansion,
``δp = S(u) θ`` at the target temperature) is undone in the inverse kinematics: the
joints are solved for the target moved by ``−δp`` at the command, again by fixed-point
iteration (:meth:`JointTermCorrection.solve`). Without a target temperature the
thermal terms act at the reference temperature, 20 °C, where they vanish.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np
import pinocchio as pin

from pincal.errors import ConvergenceError, ParameterError
from pincal.model import (
    THERMAL_REFERENCE_C,
    Mechanism,
    ParameterSet,
    deflected_joints,
    joint_term_basis,
    joint_term_shift,
    loaded_terms,
    parameters,
    undeflected_commands,
)

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
        temperature: the machine temperature at the targets [°C]; None: the thermal
            terms' reference (20 °C, no expansion).
        loaded_on: the calibrated machine whose geometry bears the loads of the
            compliances (None: ``nominal``); a compliance deflects it under its own
            loads at the configuration it deflects to (:func:`pincal.model.deflected_joints`),
            as the identification models it.
    """

    nominal: Mechanism
    params: ParameterSet
    values: np.ndarray
    temperature: float | None = None
    loaded_on: Mechanism | None = None

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
        sub = params.subset(k)
        loaded = loaded_terms(sub)
        geometry = None
        if loaded.size and np.any(values[k][loaded]):
            geometry = params.apply(nominal, params.linearise(values))
        return cls(nominal, sub, values[k].copy(), loaded_on=geometry)

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

    def at_temperature(self, celsius: float | None) -> JointTermCorrection:
        """These terms at the machine temperature ``celsius`` [°C] (None: the reference)."""
        return replace(self, temperature=None if celsius is None else float(celsius))

    def _conditions(self, m: int) -> dict[str, np.ndarray | None]:
        t = THERMAL_REFERENCE_C if self.temperature is None else self.temperature
        return {"temperature": np.full(m, t)}

    def deflection(
        self, commands: np.ndarray, conditions: Mapping[str, np.ndarray | None] | None = None
    ) -> np.ndarray:
        """Joint changes ``δq = B(u) θ`` (m, n_act) at commands ``u`` (m, n_act) [rad, m].

        ``conditions``: per-pose conditions (``{"temperature": (m,) °C}``, e.g. a held-out
        file's) instead of :attr:`temperature` for every pose.
        """
        u = np.atleast_2d(np.asarray(commands, dtype=float))
        if not self:
            return np.zeros_like(u)
        at = conditions if conditions is not None else self._conditions(len(u))
        basis = joint_term_basis(self.nominal, self.params, u, at)
        loaded = loaded_terms(self.params)
        if self.loaded_on is None or not loaded.size:
            return basis @ self.values
        basis[:, :, loaded] = 0.0  # the compliances: on the calibrated machine, deflected
        q = deflected_joints(self.loaded_on, self.params, self.values, u + basis @ self.values,
                             at)  # fmt: skip
        return q - u

    def shift(
        self, commands: np.ndarray, conditions: Mapping[str, np.ndarray | None] | None = None
    ) -> np.ndarray | None:
        """World position change (m, 3) of the measured frame at commands ``u`` [m].

        None when no term moves the frame directly. ``conditions`` as for
        :meth:`deflection`.
        """
        u = np.atleast_2d(np.asarray(commands, dtype=float))
        if not self:
            return None
        at = conditions if conditions is not None else self._conditions(len(u))
        S = joint_term_shift(self.nominal, self.params, u, at)
        return None if S is None else S @ self.values

    def solve(self, solver: Mechanism, target: pin.SE3, q: np.ndarray) -> np.ndarray:
        """The configuration reaching ``target`` with the frame's shift undone.

        Args:
            solver: the calibrated mechanism solving the inverse kinematics.
            target: the target pose of the measured frame (world).
            q: the configuration solved without the shift (the start).

        Returns:
            (nq,) configuration whose frame is at ``target − δp(u)``, ``u`` its command.

        Raises:
            ConvergenceError: the inverse kinematics or the iteration does not settle.
        """
        if self.shift(solver.actuators_of(q)[None]) is None:
            return q  # no term moves the frame (cheap: no command iteration)
        d_old = np.zeros(3)
        for _ in range(_MAX_ITER):
            u = self.commands(solver.actuators_of(q)[None])
            d = self.shift(u)
            if d is None:
                return q
            moved = pin.SE3(target.rotation, target.translation - d[0])
            q = solver.inverse_configuration(moved, q)
            if float(np.max(np.abs(d[0] - d_old))) < _TOL:
                return q
            d_old = d[0]
        raise ConvergenceError(
            f"the pose undoing the thermal shift did not settle in {_MAX_ITER} steps"
        )

    def commands(self, joints: np.ndarray) -> np.ndarray:
        """Commands (m, n_act) that move the joints to ``joints`` (m, n_act) [rad, m].

        Raises:
            ConvergenceError: the iteration does not settle (terms too large to invert).
        """
        q = np.atleast_2d(np.asarray(joints, dtype=float))
        terms: JointTermCorrection = self
        loaded = loaded_terms(self.params)
        if self.loaded_on is not None and loaded.size:
            # the compliances' deflection at the joints reached, on the calibrated machine
            q = undeflected_commands(self.loaded_on, self.params, self.values, q,
                                     self._conditions(len(q)))  # fmt: skip
            keep = np.setdiff1d(np.arange(len(self.params)), loaded)
            if not keep.size:  # compliances only: the command is found
                return q
            terms = replace(self, params=self.params.subset(keep), values=self.values[keep],
                            loaded_on=None)  # fmt: skip
        u = q.copy()
        step = 0.0
        for _ in range(_MAX_ITER):
            new = q - terms.deflection(u)
            step = float(np.max(np.abs(new - u), initial=0.0))
            u = new
            if step < _TOL:
                return u
        raise ConvergenceError(
            f"the command undoing the joint terms did not settle in {_MAX_ITER} steps (last "
            f"step {step:.3g}); the identified terms are too large for a small-deflection model"
        )
