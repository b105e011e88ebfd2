"""The identification problem: what to fit, and its whitened residual model.

:class:`IdentificationProblem` describes one problem (mechanism, parameter set,
measurements with their noise, which parameters to fit, start values). Every solver
of :func:`pincal.identification.identify` takes one and returns one
:class:`pincal.identification.IdentificationResult`.

:class:`CalibrationProblem` is its residual model: the residual of pose i is
``measured − model`` in the measured components (``[p_meas − p; log3(Rᵀ R_meas)]``),
whitened by the noise standard deviations, with the analytic identification Jacobian.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from pincal.errors import ClosureError, ConvergenceError, MeasurementError, ParameterError
from pincal.measure._measurements import Measurements
from pincal.model._closures import measurement_residual
from pincal.model._mechanism import Mechanism
from pincal.model._parameters import ParameterSet
from pincal.sensitivity._jacobian import pose_sensitivity

__all__ = ["TRIAL_FAILURES", "CalibrationProblem", "IdentificationProblem"]

#: exceptions that make a trial parameter vector unusable (model not assembled / not solved)
TRIAL_FAILURES = (ConvergenceError, ClosureError)


class CalibrationProblem:
    """Whitened residuals and Jacobian of a parameter set against measurements.

    Args:
        mech: nominal mechanism; params: parameter set (n); measurements: m poses.

    Raises:
        MeasurementError: the measurements are of other joints or another frame.
    """

    def __init__(self, mech: Mechanism, params: ParameterSet, measurements: Measurements):
        if tuple(measurements.actuated) != tuple(mech.actuated):
            raise MeasurementError(
                f"measurement columns {list(measurements.actuated)} do not match the actuated "
                f"joints {list(mech.actuated)}"
            )
        if measurements.frame != mech.measured_frame:
            raise MeasurementError(
                f"measurements are of frame {measurements.frame!r}, the model measures "
                f"{mech.measured_frame!r}"
            )
        self.mech, self.params, self.meas = mech, params, measurements
        self.rows = measurements.component_indices
        noise = measurements.noise
        m, k = len(measurements), len(self.rows)
        if measurements.std is not None:
            self.sigma = np.array(measurements.std, dtype=float)
            self.known_noise = True
        elif noise is not None and np.all(noise.std(measurements.components) > 0):
            self.sigma = np.tile(noise.std(measurements.components), (m, 1))
            self.known_noise = True
        else:
            self.sigma = np.ones((m, k))
            self.known_noise = False
        self._qs: np.ndarray | None = None
        self._cache: tuple[bytes, Mechanism] | None = None

    @property
    def solver_floor_cost(self) -> float:
        """Cost of residuals at 100× the FK tolerance: below it, data are fitted exactly."""
        return 0.5 * float(np.sum((100 * self.mech.options.tol / self.sigma) ** 2))

    @property
    def n_equations(self) -> int:
        """Scalar measurement equations: poses × measured components."""
        return len(self.meas) * len(self.rows)

    def mechanism(self, values: np.ndarray) -> Mechanism:
        """The mechanism with parameter values (n,) [SI] applied (cached for the last one)."""
        key = np.asarray(values, dtype=float).tobytes()
        if self._cache is None or self._cache[0] != key:
            mech = self.mech if not np.any(values) else self.params.apply(self.mech, values)
            self._cache = (key, mech)
        return self._cache[1]

    def cost(self, values: np.ndarray) -> float:
        """0.5·‖whitened residual‖² at ``values``; +inf when the model cannot be assembled
        or a pose cannot be solved."""
        try:
            r, _, _ = self.evaluate(values, jacobian=False)
        except TRIAL_FAILURES:
            return float("inf")
        return 0.5 * float(r @ r)

    def evaluate(self, values: np.ndarray, jacobian: bool = True):
        """Whitened residual (N,), its Jacobian (N, n) or None, and raw residuals (m, k)."""
        mech = self.mechanism(values)
        meas = self.meas
        q_prev = self._qs
        qs = np.empty((len(meas), mech.model.nq))
        r_raw = np.empty((len(meas), len(self.rows)))
        J = np.empty((len(meas), len(self.rows), len(self.params))) if jacobian else None
        for i, q_act in enumerate(meas.q_act):
            guess = q_prev[i] if q_prev is not None else None
            try:
                qs[i] = mech.configuration(q_act, guess, pose_index=i)
            except ConvergenceError:
                if guess is None:
                    raise
                qs[i] = mech.configuration(q_act, None, pose_index=i)
            R_meas = None if meas.rotations is None else meas.rotations[i]
            if jacobian:
                sens = pose_sensitivity(mech, self.params, qs[i], values)
                p, R = sens.position, sens.rotation
            else:
                oMf = mech.frame_placement(qs[i])
                p, R = oMf.translation, oMf.rotation
            r, D = measurement_residual(p, R, meas.positions[i], R_meas)
            r_raw[i] = r[self.rows]
            if jacobian:
                J[i] = -(D @ sens.jacobian)[self.rows]
        self._qs = qs
        w = 1.0 / self.sigma
        r_w = (r_raw * w).ravel()
        J_w = None if J is None else (J * w[:, :, None]).reshape(-1, len(self.params))
        return r_w, J_w, r_raw


@dataclass(frozen=True, eq=False)
class IdentificationProblem:
    """One identification problem, solved by any registered solver.

    Attributes:
        mech: nominal mechanism (the one ``params`` was built for).
        params: the n candidate parameters.
        measurements: m measured poses; their noise model / per-value std weight the
            residuals (unit weights when neither is given).
        initial: (n,) start values [m, rad] (None = zeros = nominal); parameters that are
            not fitted stay at these values.
        fit: names of the parameters to fit (None = all); parameters outside stay at
            ``initial``.
        reduce: fit only the identifiable base set of ``fit`` (True), or raise
            :class:`pincal.UnidentifiableError` when it is rank-deficient (False).

    Raises:
        ParameterError: ``initial`` of the wrong shape or non-finite; ``fit`` names a
            parameter outside ``params`` or is empty.
        MeasurementError: the measurements do not match the mechanism.
    """

    mech: Mechanism
    params: ParameterSet
    measurements: Measurements
    initial: np.ndarray | None = None
    fit: Sequence[str] | None = None
    reduce: bool = True

    def __post_init__(self) -> None:
        x0 = self.params.check_values(self.initial).copy()
        x0.setflags(write=False)
        object.__setattr__(self, "initial", x0)
        if self.fit is not None:
            names = tuple(str(n) for n in self.fit)
            unknown = [n for n in names if n not in self.params.names]
            if unknown or not names:
                raise ParameterError(
                    f"fit must name parameters of set {self.params.label!r}; unknown: {unknown}"
                    if unknown
                    else "fit is empty; name at least one parameter (or None for all)"
                )
            object.__setattr__(self, "fit", names)
        self.model  # noqa: B018 - checks the measurements against the mechanism up front

    @cached_property
    def model(self) -> CalibrationProblem:
        """The whitened residual model of this problem."""
        return CalibrationProblem(self.mech, self.params, self.measurements)

    @property
    def x0(self) -> np.ndarray:
        """(n,) start values [SI] (a copy)."""
        return np.array(self.initial, dtype=float)

    @property
    def fit_indices(self) -> np.ndarray:
        """Indices (into ``params``) of the parameters to fit, before reduction."""
        if self.fit is None:
            return np.arange(len(self.params))
        return np.array(sorted(self.params.index(n) for n in self.fit), dtype=int)
