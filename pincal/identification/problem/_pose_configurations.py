"""The measured poses' closed configurations at trial parameter values, batched.

The kinematic half of :class:`pincal.identification.CalibrationProblem`: at a parameter
vector, the parameter set linearised there, the mechanism with it applied, the actual
joint values (the commands moved by the joint terms and deflected by the loaded ones)
and the closed configurations of every measured pose, solved in one batch and started
from the last solution (or its first-order prediction). The residuals and the
Jacobian assembled on them are :mod:`pincal.identification.problem._problem`.
"""

from __future__ import annotations

import copy

import numpy as np

from pincal.errors import ConvergenceError
from pincal.measure import Measurements
from pincal.model import (
    BatchKinematics,
    Linearisation,
    Mechanism,
    ParameterSet,
    deflected_joints,
    deflection_jacobian,
    joint_term_bases,
    loaded_terms,
)
from pincal.sensitivity.kernels import predict_configurations

__all__ = ["PoseConfigurations"]


class PoseConfigurations:
    """Closed configurations of m measured poses at parameter values (the last kept).

    Args:
        mech: nominal mechanism; params: parameter set (n); measurements: m poses.

    Attributes:
        basis: (m, n_act, n) joint changes per parameter at the commands [m or rad per
            unit], the loaded terms' columns zeroed (they are evaluated at the deflected
            joints, :meth:`term_basis`); None when no term moves a joint.
        shift: (m, 3, n) the measured frame's position change per parameter [m per
            unit]; None when no term moves the frame.
        predict_starts: start each solve from the first-order prediction of the
            parameter change (switched on by Gauss–Newton for its run; other solvers
            keep the last solution).
    """

    def __init__(self, mech: Mechanism, params: ParameterSet, measurements: Measurements):
        self.mech, self.params, self.meas = mech, params, measurements
        self.basis, self.shift = joint_term_bases(mech, params, measurements)
        #: load-dependent terms (compliance): evaluated on the estimate's geometry at the
        #: deflected joint values (:mod:`pincal.model.params._deflection`), so their columns of
        #: the command's basis are zeroed; (values key, actual joint values) of the last
        self._loaded = loaded_terms(params)
        if self.basis is not None and self._loaded.size:
            self.basis = self.basis.copy()
            self.basis[:, :, self._loaded] = 0.0
        self._deflected: tuple[bytes, np.ndarray] | None = None
        self._qs: np.ndarray | None = None
        self._solved: tuple[Linearisation, Mechanism, BatchKinematics] | None = None
        self.predict_starts = False
        self._cache: tuple[bytes, Mechanism] | None = None
        #: (values key, the parameter set linearised there) of the last values evaluated
        self._linearised: tuple[bytes, Linearisation] | None = None

    def warm_copy(self) -> PoseConfigurations:
        """A copy that starts from this one's last solution and keeps its caches.

        Its predictions are off (:attr:`predict_starts`); later solves of either do
        not change the other.
        """
        new = copy.copy(self)
        new.predict_starts = False
        return new

    def linearisation(self, values: np.ndarray) -> Linearisation:
        """The parameter set linearised at values (n,) [SI] (kept for the last one)."""
        key = np.asarray(values, dtype=float).tobytes()
        if self._linearised is None or self._linearised[0] != key:
            self._linearised = (key, self.params.linearise(values))
        return self._linearised[1]

    def mechanism(self, values: np.ndarray) -> Mechanism:
        """The mechanism with parameter values (n,) [SI] applied (cached for the last one)."""
        key = np.asarray(values, dtype=float).tobytes()
        if self._cache is None or self._cache[0] != key:
            lin = self.linearisation(values)
            mech = self.mech if not np.any(values) else self.params.apply(self.mech, lin)
            self._cache = (key, mech)
        return self._cache[1]

    def _guesses(self, values: np.ndarray) -> np.ndarray | None:
        """Start configurations for a solve at ``values``.

        The last solution, moved by the first-order passive-joint prediction of the
        parameter change when predictions are on (:attr:`predict_starts`) and apply.
        """
        if self._solved is None or not self.predict_starts:
            return self._qs
        lin0, mech0, bk0 = self._solved
        pred = predict_configurations(mech0, self.params, bk0, lin0, values - lin0.values)
        return self._qs if pred is None else pred

    def solve(
        self, mech: Mechanism, values: np.ndarray
    ) -> tuple[np.ndarray, BatchKinematics | None]:
        """Closed configurations (m, nq) of the measured poses and their batch kinematics.

        Args:
            mech: the mechanism at ``values`` (:meth:`mechanism`).
            values: (n,) parameter values [SI].

        Returns:
            The configurations, warm-started (a pose the batch does not solve is solved
            alone from its last configuration, then from home), and the batch
            kinematics (None after such a fallback).

        Raises:
            ConvergenceError: a pose cannot be solved.
        """
        meas = self.meas
        q_act = self.joint_values(mech, values)
        try:
            qs, bk = mech.configurations_batch(q_act, self._guesses(values))
        except ConvergenceError:
            if self._qs is None:
                raise
            qs = np.empty((len(meas), mech.model.nq))
            for i, q_i in enumerate(q_act):
                try:
                    qs[i] = mech.configuration(q_i, self._qs[i], pose_index=i)
                except ConvergenceError:
                    qs[i] = mech.configuration(q_i, None, pose_index=i)
            bk = None
        self._qs = qs
        self._solved = None if bk is None else (self.linearisation(values), mech, bk)
        return qs, bk

    def joint_values(self, mech: Mechanism, values: np.ndarray) -> np.ndarray:
        """(m, n_act) actual joint values [m or rad] at ``values``: command, terms, deflection.

        Args:
            mech: the mechanism at ``values`` (:meth:`mechanism`).
            values: (n,) parameter values [SI].
        """
        meas = self.meas
        u = meas.q_act if self.basis is None else meas.q_act + self.basis @ values
        if not self._loaded.size:
            return u
        key = values.tobytes()
        if self._deflected is None or self._deflected[0] != key:
            q = deflected_joints(mech, self.params, values, u, meas.conditions)
            self._deflected = (key, q)
        return self._deflected[1]

    def term_basis(self, mech: Mechanism, values: np.ndarray) -> np.ndarray | None:
        """(m, n_act, n) joint changes per parameter at ``values`` (None: no terms).

        Args:
            mech: the mechanism at ``values`` (:meth:`mechanism`).
            values: (n,) parameter values [SI].
        """
        if self.basis is None or not self._loaded.size:
            return self.basis
        q = self.joint_values(mech, values)
        return deflection_jacobian(
            mech,
            self.params,
            values,
            q,
            self.basis,
            lambda v: self.params.apply(self.mech, self.params.linearise(v)),
            self.meas.conditions,
        )
