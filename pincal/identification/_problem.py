"""The identification problem: what to fit, and its whitened residual model.

:class:`IdentificationProblem` describes one problem (mechanism, parameter set,
measurements with their noise, which parameters to fit, start values). Every solver
of :func:`pincal.identification.identify` takes one and returns one
:class:`pincal.identification.IdentificationResult`.

:class:`CalibrationProblem` is its residual model: the residual of pose i is
``measured − model`` in the measured components (``[p_meas − p; log3(Rᵀ R_meas)]``),
whitened by the noise standard deviations, with the analytic identification Jacobian.

The standard deviations are, in this order: the measurements' per-value ``std``, the
declared noise model (the ``noise`` argument, else the file's ``# noise:`` header), or —
when neither is given (the normal case for real data) — estimated per block
(position, orientation) from the residuals by variance-component estimation
(:mod:`pincal.identification._noise`). A residual model whose noise is still to be
estimated has ``noise_source == "estimate"`` and must be re-weighted
(:meth:`CalibrationProblem.with_block_std`) before it is fitted: it never fits with
silent unit weights.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from pincal.errors import ClosureError, ConvergenceError, MeasurementError, ParameterError
from pincal.measure._measurements import Measurements, NoiseModel
from pincal.model._closures import measurement_residual
from pincal.model._mechanism import Mechanism
from pincal.model._parameters import ParameterSet
from pincal.sensitivity._jacobian import pose_sensitivity

__all__ = ["BLOCKS", "TRIAL_FAILURES", "CalibrationProblem", "IdentificationProblem"]

#: exceptions that make a trial parameter vector unusable (model not assembled / not solved)
TRIAL_FAILURES = (ConvergenceError, ClosureError)
#: noise blocks: name → measured components of the block
BLOCKS = {"position": ("x", "y", "z"), "orientation": ("rx", "ry", "rz")}


class CalibrationProblem:
    """Whitened residuals and Jacobian of a parameter set against measurements.

    Args:
        mech: nominal mechanism; params: parameter set (n); measurements: m poses.
        noise: declared instrument noise (a :class:`NoiseModel` or ``{"position": mm,
            "orientation": mrad}``); overrides the measurements' noise model. A zero σ
            of a measured block counts as not declared.

    Attributes:
        sigma: (m, k) standard deviations of the residuals [m, rad].
        noise_source: ``"per-pose"``, ``"declared"``, ``"estimated"`` (re-weighted by
            :meth:`with_block_std`) or ``"estimate"`` (still to be estimated; ``sigma``
            is a placeholder that must not be fitted with).
        blocks: {block name: column indices into the measured components}.

    Raises:
        MeasurementError: the measurements are of other joints or another frame, or a
            bad noise specification.
    """

    def __init__(
        self,
        mech: Mechanism,
        params: ParameterSet,
        measurements: Measurements,
        noise: NoiseModel | Mapping[str, float] | None = None,
    ):
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
        declared = NoiseModel.from_spec(noise)
        noise = declared if declared is not None else measurements.noise
        comps = measurements.components
        self.blocks = {
            b: np.array([j for j, c in enumerate(comps) if c in cs], dtype=int)
            for b, cs in BLOCKS.items()
            if any(c in cs for c in comps)
        }
        m, k = len(measurements), len(self.rows)
        if measurements.std is not None and declared is None:
            self.sigma = np.array(measurements.std, dtype=float)
            self.noise_source = "per-pose"
        elif noise is not None and np.all(noise.std(comps) > 0):
            self.sigma = np.tile(noise.std(comps), (m, 1))
            self.noise_source = "declared"
        else:
            self.sigma = np.ones((m, k))
            self.noise_source = "estimate"
        self._qs: np.ndarray | None = None
        self._cache: tuple[bytes, Mechanism] | None = None

    @property
    def known_noise(self) -> bool:
        """Whether ``sigma`` holds the noise (declared, per-pose or estimated)."""
        return self.noise_source != "estimate"

    @property
    def sigma_floor(self) -> float:
        """Smallest σ an estimate may take [m, rad]: 100× the kinematic solver's tolerance."""
        return 100 * self.mech.options.tol

    def block_std(self) -> dict[str, float]:
        """{block: σ} when each block has one σ for all its poses (NaN otherwise)."""
        out = {}
        for b, cols in self.blocks.items():
            vals = self.sigma[:, cols]
            out[b] = float(vals.flat[0]) if np.all(vals == vals.flat[0]) else float("nan")
        return out

    def with_block_std(self, std: Mapping[str, float]) -> CalibrationProblem:
        """A copy weighted by one σ per block (``{"position": m, "orientation": rad}``).

        The copy has ``noise_source == "estimated"`` and shares the nominal mechanism
        and the last configurations (as start guesses) with this one.

        Raises:
            MeasurementError: a measured block without a finite σ > 0.
        """
        sigma = np.empty_like(self.sigma)
        for b, cols in self.blocks.items():
            v = std.get(b)
            if v is None or not np.isfinite(v) or v <= 0:
                raise MeasurementError(f"noise σ of the {b} block must be finite and > 0, got {v}")
            sigma[:, cols] = float(v)
        new = CalibrationProblem(self.mech, self.params, self.meas)
        new.sigma, new.noise_source = sigma, "estimated"
        new._qs = self._qs
        return new

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
        measurements: m measured poses; their per-value std / noise model weight the
            residuals (estimated from the residuals when neither is given).
        initial: (n,) start values [m, rad] (None = zeros = nominal); parameters that are
            not fitted stay at these values.
        fit: names of the parameters to fit (None = all); parameters outside stay at
            ``initial``.
        reduce: fit only the identifiable base set of ``fit`` (True), or raise
            :class:`pincal.UnidentifiableError` when it is rank-deficient (False).
        noise: declared instrument noise (:class:`pincal.measure.NoiseModel` or
            ``{"position": mm, "orientation": mrad}``), overriding the measurements'
            own; None: the measurements' per-value std or noise model, else the noise is
            estimated from the residuals (variance components per block).

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
    noise: NoiseModel | Mapping[str, float] | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "noise", NoiseModel.from_spec(self.noise))
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
        return CalibrationProblem(self.mech, self.params, self.measurements, self.noise)

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
