"""Parameter identification: one problem → one result, for every registered solver.

:func:`identify` counts the equations against what is fitted (the identifiable base set
of the parameters to fit), runs the solver chosen by name and computes the common
result: covariance ``(Jᵀ W J)⁻¹`` at the solution (the Cramér–Rao bound for Gaussian
noise), residual statistics and the calibrated mechanism. When the data declare no
noise, the σ of each block (position, orientation) is estimated from the residuals by
variance-component estimation (:mod:`pincal.identification._noise`); the weights used
are reported in ``result.weighting``.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from typing import Any

import numpy as np
from threadpoolctl import threadpool_limits

from pincal.errors import SolverOptionError, TooFewPosesError, UnidentifiableError
from pincal.identification._finish import finish, settle
from pincal.identification._identification_problem import IdentificationProblem
from pincal.identification._instrument_identify import joint_fit
from pincal.identification._instrument_problem import Dataset
from pincal.identification._noise import initial_weights, weighted_fit
from pincal.identification._options import GaussNewtonOptions, LMOptions
from pincal.identification._outcome import Progress
from pincal.identification._problem import CalibrationProblem
from pincal.identification._result import IdentificationResult, ResidualStats
from pincal.identification._solvers import solver
from pincal.measure import Measurements
from pincal.model import Mechanism, ParameterSet, degenerate_translations
from pincal.sensitivity import Identifiability, analyse_jacobian, closure_breaking
from pincal.sensitivity.kernels import batch_applies

__all__ = ["identify"]

log = logging.getLogger(__name__)
def _fit_set(
    problem: IdentificationProblem, J0: np.ndarray, model: CalibrationProblem
) -> tuple[np.ndarray, Identifiability]:
    """Indices fitted and the analysis at the start.

    The fitted set is the identifiable base set of ``problem.fit`` without the parameters
    that break loop closure and without the translations inside emulated ball or
    universal joints (:func:`pincal.model.degenerate_translations`), both reported apart.
    """
    params = problem.params
    candidates = problem.fit_indices
    breaking = np.zeros(len(params), dtype=bool)
    # closures without redundant rows break nothing where the batched Jacobian applies
    # (the start evaluation solved every pose there): no second pass is needed
    mech = model.mechanism(problem.x0)
    if mech.closures and (mech.n_closure_rows > mech.closure_rank or not batch_applies(mech)):
        breaking = closure_breaking(problem.mech, params, problem.pose_file.q_act, problem.x0)
    splitting = np.isin(params.names, degenerate_translations(problem.mech))
    J0 = model.structural_jacobian(problem.x0)  # not the measured deviation's mixing
    ident = analyse_jacobian(J0, params.names, breaks_closure=breaking, splits_joint=splitting,
                             units=params.units)  # fmt: skip
    if np.array_equal(candidates, np.arange(len(params))):
        sub = ident  # fitting every parameter: the same analysis
    else:
        sub = analyse_jacobian(
            J0[:, candidates],
            tuple(params.names[i] for i in candidates),
            breaks_closure=breaking[candidates],
            splits_joint=splitting[candidates],
        )
    n, n_eq = candidates.size, model.n_equations
    if sub.rank < n and sub.rank >= n_eq:
        rows = len(model.rows)
        raise TooFewPosesError(
            f"{len(problem.pose_file)} poses × {rows} components = {n_eq} equations for "
            f"{n} parameters, and all {n_eq} are used up (rank {sub.rank}): the data cannot "
            f"tell which parameters are identifiable; measure at least {-(-n // rows)} poses"
        )
    if sub.full_rank:
        return candidates, ident
    if not problem.reduce:
        raise UnidentifiableError(
            f"only {sub.rank} of {n} parameters are identifiable from these poses:\n"
            + "\n".join(sub.describe()),
            sub.unidentifiable_names,
        )
    return candidates[sub.base], ident


def identify(
    problem: IdentificationProblem | Mechanism,
    params: ParameterSet | str | None = None,
    measurements: Measurements | Sequence[Dataset] | None = None,
    method: str = "gauss-newton",
    *,
    options: Any = None,
    initial: np.ndarray | None = None,
    fit: Any = None,
    reduce: bool = True,
    progress: Progress = None,
    noise: Any = None,
) -> IdentificationResult:
    """Identify parameter values from measurements.

    Call it as ``identify(problem, method=..., options=...)`` with an
    :class:`IdentificationProblem`, or as ``identify(mech, params, measurements,
    method, ...)`` (``initial``, ``fit`` and ``reduce`` then build the problem). One pose
    file is fitted by its batched residual model, by any registered solver; several
    data sets or instrument files by the joint model of machine and instrument
    unknowns (``"gauss-newton"`` or ``"lm"``; the instrument values and the gauge are
    in ``result.annotations``, see also
    :func:`pincal.identification.identify_instruments`). Both end in the same
    finishing step.

    Args:
        problem: an :class:`IdentificationProblem`, or the nominal mechanism.
        params: the n parameters (mechanism form only).
        measurements: m measured poses (with a mechanism), or a sequence of data sets
            (see :class:`IdentificationProblem`).
        method: a registered solver: ``"gauss-newton"``, ``"lm"``, ``"qpso"``,
            ``"qpso-stepwise"`` or ``"step-planned"`` (see ``METHODS``).
        options: the method's options dataclass (``GaussNewtonOptions``, ``LMOptions``,
            ``QPSOOptions``, ``StepPlanningOptions``; default: its defaults).
        initial: (n,) start values [m, rad] (mechanism form only; None = nominal); see
            :class:`IdentificationProblem`.
        fit: names of the parameters to fit (mechanism form only; None = all).
        reduce: fit only the identifiable base set of ``fit`` (mechanism form only);
            False raises when it is rank-deficient.
        noise: declared instrument noise (mechanism form only; a ``NoiseModel`` or
            ``{"position": mm, "orientation": mrad}``); without a declared noise, it is
            estimated from the residuals.
        progress: optional callback ``(iteration, cost)``.

    Returns:
        IdentificationResult.

    Raises:
        TooFewPosesError: fewer equations than the identifiable parameters need.
        UnidentifiableError: rank-deficient and ``reduce`` is False.
        SolverOptionError: unknown method or options of the wrong type / range; a
            method other than ``"gauss-newton"`` or ``"lm"`` for a joint fit.
        MeasurementError, ParameterError: inconsistent inputs.
        NoiseEstimationError: no noise declared and too few redundant equations to
            estimate it.
    """
    if isinstance(problem, IdentificationProblem):
        if params is not None or measurements is not None:
            raise SolverOptionError(
                "with an IdentificationProblem, give only method= and options= "
                "(e.g. identify(problem, method='lm'))"
            )
        if initial is not None or fit is not None or reduce is not True or noise is not None:
            raise SolverOptionError(
                "initial / fit / reduce / noise belong in the IdentificationProblem"
            )
    else:
        if not isinstance(params, ParameterSet) or measurements is None:
            raise SolverOptionError(
                "identify(mech, params, measurements, method): params must be a ParameterSet "
                f"and measurements a Measurements (or a list of data sets), got "
                f"{type(params).__name__} and {type(measurements).__name__}"
            )
        problem = IdentificationProblem(
            problem, params, measurements, initial, fit, reduce, noise
        )
    if problem.joint:  # several data sets or instrument files: the joint fit
        return joint_fit(problem.joint_model, method, options, progress, problem.weak_bound).result
    entry = solver(method)
    opts = entry.check_options(options)
    with threadpool_limits(1):  # small dense solves: threaded BLAS only adds contention
        return _run(problem, method, entry, opts, progress)


def _run(problem: IdentificationProblem, method: str, entry: Any, opts: Any, progress: Progress):
    """The body of :func:`identify` (checked arguments), one BLAS thread."""
    model = problem.model
    x0 = problem.x0
    _, J0, raw0 = model.evaluate(x0)
    model, J0 = initial_weights(model, J0, raw0)
    free, ident = _fit_set(problem, J0, model)
    n_fit = problem.fit_indices.size
    prefix = ""
    if free.size < n_fit:
        held = np.setdiff1d(problem.fit_indices, free)
        n_break = int(np.isin(held, ident.breaks_closure).sum())
        n_split = int(np.isin(held, ident.splits_joint).sum())
        why = [f"{n_break} break loop closure"] if n_break else []
        why += [f"{n_split} would split an emulated ball or universal joint"] if n_split else []
        prefix = (
            f"identified the {free.size} base parameters; held {n_fit - free.size} "
            f"unidentifiable ones at their initial values"
            + (f" ({'; '.join(why)})" if why else "")
            + ". "
        )
        log.info(prefix)
    out, model, weighting = weighted_fit(model, entry, x0, free, opts, progress)
    local = isinstance(opts, (GaussNewtonOptions, LMOptions))
    prior = opts.prior_weights(x0.size) if local else None
    settled = settle(model, out, free)
    comps = tuple(problem.pose_file.components)
    result, _ = finish(
        model, settled, method=method, params=problem.params, raw0=raw0,
        stats=lambda raw: ResidualStats.from_residuals(raw, comps), residuals=settled.raw,
        initial_values=problem.x0, prefix=prefix, prior=None if prior is None else prior[0],
        identifiability=ident, weighting=weighting, initial_residuals=raw0, components=comps,
    )  # fmt: skip
    return result
