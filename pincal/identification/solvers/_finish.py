"""The one finishing step of every identification: solver outcome → IdentificationResult.

Both residual models end here — the batched :class:`CalibrationProblem` of one pose file
and the joint :class:`InstrumentProblem` of several datasets. :func:`settle` evaluates
the model at the solver's answer (and, for the joint fit, accepts a stop at the noise
floor); :func:`finish` turns that into the :class:`IdentificationResult`: reduced χ²
(χ²/ν), the rank-revealing covariance of the fitted unknowns from an SVD of their
whitened Jacobian (:func:`pincal.identification.solvers._covariance.fitted_covariance`), the
residual statistics before and after, the message and the calibrated mechanism.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from pincal.identification._weighting import Weighting, data_leverage
from pincal.identification.problem import ResidualModel
from pincal.identification.results import (
    IdentificationResult,
    JointDetails,
    ResidualStats,
    SolverOutcome,
)
from pincal.identification.solvers._covariance import fitted_covariance
from pincal.model import ParameterSet
from pincal.sensitivity import Identifiability

__all__ = ["ResidualModel", "Settled", "finish", "settle"]

@dataclass(frozen=True)
class Settled:
    """A residual model evaluated at the solver's answer.

    Attributes:
        out: the solver's outcome.
        fitted: (f,) indices of the fitted unknowns (the solver's own set when it
            reports one, else the free set it was given).
        r: (N,) whitened residual at ``out.x``; Jf: (N, f) its Jacobian in the fitted
            unknowns (columns in ``fitted`` order).
        raw: the model's raw residuals at ``out.x`` [m, rad] ((m, k) for a pose file, a
            list of (m_i, k_i) per dataset for a joint fit).
        success, message: the solver's, or success at the noise floor (see :func:`settle`).
    """

    out: SolverOutcome
    fitted: np.ndarray
    r: np.ndarray
    Jf: np.ndarray
    raw: Any
    success: bool
    message: str

    @property
    def dof(self) -> int:
        """Redundancy ν = N − f (at least 1)."""
        return max(self.r.size - self.fitted.size, 1)

    @property
    def reduced_chi2(self) -> float:
        """χ²/ν of the whitened residual."""
        return float(self.r @ self.r) / self.dof


def settle(
    model: ResidualModel, out: SolverOutcome, free: np.ndarray, noise_floor: bool = False
) -> Settled:
    """Evaluate ``model`` at the solver's answer.

    Args:
        model: the residual model the solver ran on.
        out: its outcome.
        free: (f,) the indices it was asked to fit.
        noise_floor: accept an unconverged stop when a further Gauss–Newton step
            promises less than the kinematic solver's precision changes the cost (100×
            its tolerance per reading): at the noise floor of exact data a step may
            promise less than that jitter.
    """
    fitted = free if out.fitted is None else np.asarray(out.fitted, dtype=int)
    r, J, raw = model.evaluate(out.x)
    Jf = J[:, fitted]
    success, message = out.success, out.message
    if noise_floor and not success:
        step = np.linalg.lstsq(Jf, -r, rcond=None)[0]
        predicted = 0.5 * float(r @ r - np.sum((r + Jf @ step) ** 2))
        sigma = model.sigma
        sig = np.concatenate([s.ravel() for s in (sigma if isinstance(sigma, list) else [sigma])])
        jitter = float(np.sum(np.abs(r) * 100 * model.mech.options.tol / sig))
        if predicted <= max(jitter, 1e-9 * float(r @ r)):
            success = True
            message = (
                f"converged (noise floor: a further step promises {predicted:.3g}, below the "
                f"kinematic precision {jitter:.3g} of the cost; solver: {out.message})"
            )
    return Settled(out, fitted, r, Jf, raw, success, message)


def finish(
    model: ResidualModel,
    s: Settled,
    *,
    method: str,
    params: ParameterSet,
    raw0: Any,
    identifiability: Identifiability,
    stats: Callable[[Any], ResidualStats],
    residuals: np.ndarray,
    initial_values: np.ndarray,
    prefix: str = "",
    prior: tuple[np.ndarray, np.ndarray] | None = None,
    weighting: Weighting | None = None,
    initial_residuals: np.ndarray | None = None,
    components: tuple[str, ...] = (),
    joint: JointDetails | None = None,
) -> tuple[IdentificationResult, np.ndarray]:
    """The :class:`IdentificationResult` of a settled fit.

    The covariance is the posterior one of the fitted unknowns (data, plus ``prior``
    where given), scaled by χ²/ν when the noise was not known
    (``model.known_noise``); the result holds its machine block, in name order. With a
    prior, ν is the regularised fit's redundancy N − tr(H) (H the data rows' hat matrix
    of the data and prior rows), not N − f.

    Args:
        model: the residual model.
        s: the model settled at the solution (:func:`settle`).
        method: the solver's name.
        params: the n machine parameters (the first n unknowns of ``model``).
        raw0: raw residuals at the start.
        stats: raw residuals → residual statistics (applied to ``raw0`` and ``s.raw``).
        residuals: the residual table the result records at the solution.
        initial_values: (n,) the recorded start values [SI].
        prefix: text before the solver's message (what was held, warnings).
        prior: (1/σ (n_x,), mean (n_x,)) of the prior on every unknown, weight 0 where
            there is none (None: no prior); recorded on the result.
        identifiability: the analysis at the start (recorded as given).
        weighting: the noise σ used (recorded as given).
        initial_residuals: (m, k) raw residuals at the start (recorded as given).
        components: names of the residual columns (recorded as given).
        joint: a joint fit's own outcome (recorded as given).

    Returns:
        The result and the covariance (f, f) of every fitted unknown, in index order.
    """
    n = len(params)
    chi2 = s.reduced_chi2
    if prior is not None:  # what the prior holds uses up no equation (see data_leverage)
        used = float(np.sum(data_leverage(s.Jf, prior[0][s.fitted])))
        chi2 = float(s.r @ s.r) / max(s.r.size - used, 1.0)
    cov_m, mask, cov = fitted_covariance(
        s.Jf, s.fitted, n, None if prior is None else prior[0][s.fitted],
        1.0 if model.known_noise else chi2,
    )  # fmt: skip
    x = np.asarray(s.out.x, dtype=float)
    result = IdentificationResult(
        method=method,
        names=params.names,
        units=params.units,
        full_values=x[:n].copy(),
        identified=mask,
        std=np.sqrt(np.clip(np.diag(cov_m), 0.0, None)),
        covariance=cov_m,
        before=stats(raw0),
        after=stats(s.raw),
        reduced_chi2=chi2,
        iterations=s.out.iterations,
        success=s.success,
        message=prefix + s.message,
        cost_history=tuple(s.out.history),
        residuals=residuals,
        initial_values=initial_values,
        n_equations=model.n_equations,
        model=model.mech.name,
        preset=params.label,
        extras=s.out.extras,
        parameter_set=params,
        calibrated_mechanism=model.mechanism(x),
        identifiability=identifiability,
        joint=joint,
        weighting=weighting,
        initial_residuals=initial_residuals,
        components=components,
        prior=prior,
    )
    return result, cov
