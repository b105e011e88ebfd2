"""Parameter identification: measurements → identified parameters with uncertainties.

The residual of pose i is ``measured − model`` in the measured components
(``[p_meas − p; log3(Rᵀ R_meas)]``), whitened by the noise model's standard
deviations. Gauss–Newton uses the analytic identification Jacobian with the exact
derivative of the rotation residual; LM delegates to
``scipy.optimize.least_squares`` (robust losses available). The covariance is
``(Jᵀ W J)⁻¹`` at the solution (scaled by the residual variance when no noise model
is given), i.e. the Cramér–Rao bound for Gaussian noise.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.optimize

from pincal.errors import (
    ConvergenceError,
    MeasurementError,
    ParameterError,
    TooFewPosesError,
    UnidentifiableError,
)
from pincal.identification._qpso_identify import QPSOOptions, qpso_identify
from pincal.measure._measurements import Measurements
from pincal.model._closures import measurement_residual
from pincal.model._mechanism import Mechanism
from pincal.model._parameters import ParameterSet
from pincal.sensitivity._identifiability import Identifiability, analyse_jacobian
from pincal.sensitivity._jacobian import pose_sensitivity

__all__ = ["METHODS", "CalibrationProblem", "IdentificationResult", "ResidualStats", "identify"]

log = logging.getLogger(__name__)
METHODS = ("gauss-newton", "lm", "qpso", "qpso-stepwise")


@dataclass(frozen=True)
class ResidualStats:
    """Residual statistics over the measured poses.

    Attributes:
        rms_position, max_position: of the position-error norm per pose [m] (NaN if
            position is not measured).
        rms_orientation, max_orientation: of the rotation-error norm per pose [rad]
            (NaN if orientation is not measured).
    """

    rms_position: float
    max_position: float
    rms_orientation: float
    max_orientation: float

    @classmethod
    def from_residuals(cls, r: np.ndarray, components: tuple[str, ...]) -> ResidualStats:
        """From unweighted residuals (m, k) in the given components."""
        pos = [i for i, c in enumerate(components) if c in ("x", "y", "z")]
        rot = [i for i, c in enumerate(components) if c.startswith("r")]
        out = []
        for cols in (pos, rot):
            if cols:
                norms = np.linalg.norm(r[:, cols], axis=1)
                out += [float(np.sqrt(np.mean(norms**2))), float(norms.max())]
            else:
                out += [float("nan"), float("nan")]
        return cls(*out)


@dataclass(frozen=True)
class IdentificationResult:
    """Outcome of :func:`identify`.

    Attributes:
        params: the parameters that were identified (the base set when reduced).
        values: (n,) identified values [m, rad].
        std: (n,) standard deviations [m, rad].
        covariance: (n, n).
        before, after: residual statistics at the initial and identified values.
        reduced_chi2: weighted residual sum of squares / (N − n).
        iterations: solver iterations.
        success: whether the solver converged.
        message: solver message, including any parameter reduction.
        calibrated: the mechanism with the identified values applied.
        identifiability: the analysis at the initial values.
        fixed: names of parameters that were held at their initial values (unidentifiable).
        cost_history: 0.5·‖weighted residual‖² per iteration.
        residuals: (m, k) unweighted residuals at the solution.
        method: "gauss-newton" or "lm".
    """

    params: ParameterSet
    values: np.ndarray
    std: np.ndarray
    covariance: np.ndarray
    before: ResidualStats
    after: ResidualStats
    reduced_chi2: float
    iterations: int
    success: bool
    message: str
    calibrated: Mechanism
    identifiability: Identifiability
    fixed: tuple[str, ...]
    cost_history: tuple[float, ...]
    residuals: np.ndarray
    method: str

    def table(self) -> list[tuple[str, float, float, str]]:
        """(name, value, std, unit) per identified parameter [SI]."""
        return list(zip(self.params.names, self.values, self.std, self.params.units, strict=True))


class CalibrationProblem:
    """Whitened residuals and Jacobian of a parameter set against measurements.

    Args:
        mech: nominal mechanism; params: parameter set (n); measurements: m poses.
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
        return len(self.meas) * len(self.rows)

    def mechanism(self, values: np.ndarray) -> Mechanism:
        key = np.asarray(values, dtype=float).tobytes()
        if self._cache is None or self._cache[0] != key:
            mech = self.mech if not np.any(values) else self.params.apply(self.mech, values)
            self._cache = (key, mech)
        return self._cache[1]

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


def _gauss_newton(
    problem: CalibrationProblem,
    x0: np.ndarray,
    free: np.ndarray,
    max_iterations: int,
    xtol: float,
    regularization: float,
    progress: Callable[[int, float], None] | None,
):
    x = x0.copy()
    r, J, _ = problem.evaluate(x)
    cost = 0.5 * float(r @ r)
    history = [cost]
    message, success = "maximum iterations reached", False
    it = 0
    for it in range(1, max_iterations + 1):
        Jf = J[:, free]
        if regularization > 0:
            A = np.vstack([Jf, np.sqrt(regularization) * np.eye(free.size)])
            b = np.concatenate([r, np.sqrt(regularization) * (x[free] - x0[free])])
        else:
            A, b = Jf, r
        step = -np.linalg.lstsq(A, b, rcond=None)[0]
        predicted = cost - 0.5 * float(np.sum((b + A @ step) ** 2))
        if predicted <= 1e-12 * cost + 1e-24 * history[0]:
            message, success = "converged (predicted decrease below 1e-12 of the cost)", True
            break
        alpha = 1.0
        for _ in range(20):
            x_try = x.copy()
            x_try[free] += alpha * step
            try:
                r_try, _, _ = problem.evaluate(x_try, jacobian=False)
                cost_try = 0.5 * float(r_try @ r_try)
            except ConvergenceError:
                cost_try = np.inf
            if cost_try < cost:
                break
            alpha *= 0.5
        else:
            # exact data: the residual is at the kinematic solver's precision
            success = cost <= problem.solver_floor_cost or cost <= 1e-20 * history[0]
            message = "converged (solver precision)" if success else "no decrease along the step"
            break
        x = x_try
        small = np.linalg.norm(alpha * step) <= xtol * (np.linalg.norm(x[free]) + xtol)
        r, J, _ = problem.evaluate(x)
        cost = 0.5 * float(r @ r)
        history.append(cost)
        if progress:
            progress(it, cost)
        if small:
            message, success = "converged (step below tolerance)", True
            break
    return x, it, history, success, message


def _levenberg_marquardt(
    problem: CalibrationProblem,
    x0: np.ndarray,
    free: np.ndarray,
    max_iterations: int,
    xtol: float,
    loss: str,
    progress: Callable[[int, float], None] | None,
):
    history: list[float] = []
    cache: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}

    def full(z):
        x = x0.copy()
        x[free] = z
        return x

    def both(z):
        key = z.tobytes()
        if key not in cache:
            cache.clear()
            r, J, _ = problem.evaluate(full(z))
            cache[key] = (r, J[:, free])
            history.append(0.5 * float(r @ r))
            if progress:
                progress(len(history), history[-1])
        return cache[key]

    method = "lm" if loss == "linear" else "trf"
    sol = scipy.optimize.least_squares(
        lambda z: both(z)[0],
        x0[free],
        jac=lambda z: both(z)[1],
        method=method,
        loss=loss,
        x_scale="jac",
        xtol=max(xtol, 1e-15),
        ftol=1e-15,
        gtol=1e-15,
        max_nfev=max_iterations * 10,
    )
    return full(sol.x), int(sol.nfev), history, bool(sol.success), str(sol.message)


def identify(
    mech: Mechanism,
    params: ParameterSet,
    measurements: Measurements,
    method: str = "gauss-newton",
    *,
    initial: np.ndarray | None = None,
    reduce: bool = True,
    loss: str = "linear",
    regularization: float = 0.0,
    max_iterations: int = 50,
    xtol: float = 1e-10,
    progress: Callable[[int, float], None] | None = None,
    qpso: QPSOOptions | None = None,
) -> IdentificationResult:
    """Identify parameter values from measurements.

    Args:
        mech: nominal mechanism (the one ``params`` was built for).
        params: the n parameters to identify.
        measurements: m measured poses.
        method: ``"gauss-newton"``, ``"lm"`` (scipy least_squares), ``"qpso"`` or
            ``"qpso-stepwise"`` (seed 003, see :mod:`pincal.identification._qpso_identify`).
        initial: (n,) starting values [SI] (default zeros = nominal).
        reduce: hold unidentifiable parameters at their initial value and identify the
            base set (True), or raise :class:`UnidentifiableError` (False).
        loss: robust loss for ``lm`` (``linear``, ``huber``, ``soft_l1``, ``cauchy``...).
        regularization: Tikhonov weight λ on ``‖x − initial‖²`` (whitened units), GN only.
        max_iterations: iteration limit.
        xtol: relative step tolerance.
        progress: optional callback ``(iteration, cost)``.
        qpso: settings of the QPSO methods (default: the seed's N = 80, t_max = 300, ±0.05 mm).

    Raises:
        TooFewPosesError, UnidentifiableError, MeasurementError, ParameterError.
    """
    if method not in METHODS:
        raise ParameterError(f"unknown identification method {method!r}; choose from {METHODS}")
    problem = CalibrationProblem(mech, params, measurements)
    n = len(params)
    if problem.n_equations < n:
        raise TooFewPosesError(
            f"{len(measurements)} poses × {len(problem.rows)} components = "
            f"{problem.n_equations} equations for {n} parameters; measure at least "
            f"{-(-n // len(problem.rows))} poses"
        )
    x0 = params.check_values(initial)
    _, J0, raw0 = problem.evaluate(x0)
    ident = analyse_jacobian(J0, params.names)
    message_prefix = ""
    free = np.arange(n)
    if not ident.full_rank:
        if not reduce:
            raise UnidentifiableError(
                f"only {ident.rank} of {n} parameters are identifiable from these poses:\n"
                + "\n".join(ident.describe()),
                ident.unidentifiable_names,
            )
        free = ident.base
        message_prefix = (
            f"identified the {ident.rank} base parameters; held {n - ident.rank} "
            f"unidentifiable ones at their initial values. "
        )
        log.info(message_prefix)
    if problem.n_equations < free.size:
        raise TooFewPosesError(f"{problem.n_equations} equations for {free.size} parameters")
    if method == "gauss-newton":
        x, iters, history, success, message = _gauss_newton(
            problem, x0, free, max_iterations, xtol, regularization, progress
        )
    elif method.startswith("qpso"):
        found = qpso_identify(problem, x0, free, stepwise=method == "qpso-stepwise", options=qpso)
        x, iters, history = found.values, found.iterations, list(found.history)
        success, message = found.cost <= found.initial_cost, found.message
    else:
        x, iters, history, success, message = _levenberg_marquardt(
            problem, x0, free, max_iterations, xtol, loss, progress
        )
    r, J, raw = problem.evaluate(x)
    Jf = J[:, free]
    dof = max(problem.n_equations - free.size, 1)
    chi2 = float(r @ r) / dof
    JtJ_inv = np.linalg.pinv(Jf.T @ Jf)
    cov = JtJ_inv if problem.known_noise else JtJ_inv * chi2
    sub = params.subset(free)
    comps = measurements.components
    return IdentificationResult(
        params=sub,
        values=x[free],
        std=np.sqrt(np.diag(cov)),
        covariance=cov,
        before=ResidualStats.from_residuals(raw0, comps),
        after=ResidualStats.from_residuals(raw, comps),
        reduced_chi2=chi2,
        iterations=iters,
        success=success,
        message=message_prefix + message,
        calibrated=problem.mechanism(x),
        identifiability=ident,
        fixed=tuple(params.names[i] for i in ident.unidentifiable),
        cost_history=tuple(history),
        residuals=raw,
        method=method,
    )
