"""Parameter identification: one problem → one result, for every registered solver.

:func:`identify` counts the equations against what is fitted (the identifiable base set
of the parameters to fit), runs the solver chosen by name and computes the common
result: covariance ``(Jᵀ W J)⁻¹`` at the solution (the Cramér–Rao bound for Gaussian
noise), residual statistics and the calibrated mechanism. When the data declare no
noise, the σ of each block (position, orientation) is estimated from the residuals by
variance-component estimation (:mod:`pincal.identification.solvers._noise`); the weights used
are reported in ``result.weighting``. The sequence is the one fit driver's
(:func:`pincal.identification.solvers._driver.drive`) with the pose file's set rule
(:class:`pincal.identification.problem._fit_set.StructuralBase`).
"""

from __future__ import annotations

import functools
from collections.abc import Mapping, Sequence

import numpy as np
from threadpoolctl import ThreadpoolController

from pincal.errors import SolverOptionError
from pincal.identification._held import with_held
from pincal.identification._instrument_identify import joint_fit
from pincal.identification._options import GaussNewtonOptions, LMOptions
from pincal.identification.problem import (
    CalibrationProblem,
    Dataset,
    IdentificationProblem,
    StructuralBase,
    WeakBound,
)
from pincal.identification.results import IdentificationResult, Progress, ResidualStats
from pincal.identification.solvers import (
    FitPolicy,
    Solver,
    SolverOptions,
    drive,
    finish,
    fitted_machine_count,
    solver,
)
from pincal.measure import Measurements, NoiseModel
from pincal.model import Mechanism, ParameterSet, degenerate_translations
from pincal.sensitivity import closure_breaking
from pincal.sensitivity.kernels import batch_applies

__all__ = ["fitted_at_start", "identify"]


def _base_rule(problem: IdentificationProblem, model: CalibrationProblem) -> StructuralBase:
    """The base-set rule of a pose file: candidates ``problem.fit``, closure and joints held.

    The parameters that break loop closure and the translations inside emulated ball or
    universal joints (:func:`pincal.model.degenerate_translations`) are held and
    reported apart.
    """
    params = problem.params
    breaking = np.zeros(len(params), dtype=bool)
    # closures without redundant rows break nothing where the batched Jacobian applies
    # (the start evaluation solved every pose there): no second pass is needed
    mech = model.mechanism(problem.x0)
    if mech.closures and (mech.n_closure_rows > mech.closure_rank or not batch_applies(mech)):
        breaking = closure_breaking(problem.mech, params, problem.pose_file.q_act, problem.x0)
    splitting = np.isin(params.names, degenerate_translations(problem.mech))
    return StructuralBase(
        problem.fit_indices, breaking, splitting, problem.reduce, len(problem.pose_file)
    )


def identify(
    problem: IdentificationProblem | Mechanism,
    params: ParameterSet | str | None = None,
    measurements: Measurements | Sequence[Dataset] | None = None,
    method: str = "gauss-newton",
    *,
    options: SolverOptions | None = None,
    initial: np.ndarray | None = None,
    fit: Sequence[str] | None = None,
    reduce: bool = True,
    progress: Progress = None,
    noise: NoiseModel | Mapping[str, float] | None = None,
) -> IdentificationResult:
    """Identify parameter values from measurements.

    Call it as ``identify(problem, method=..., options=...)`` with an
    :class:`IdentificationProblem`, or as ``identify(mech, params, measurements,
    method, ...)`` (``initial``, ``fit`` and ``reduce`` then build the problem). One pose
    file is fitted by its batched residual model, by any registered solver; several
    data sets or instrument files by the joint model of machine and instrument
    unknowns (``"gauss-newton"`` or ``"lm"``; the instrument values and the gauge are
    in ``result.joint``, see also :func:`pincal.identification.identify_instruments`).
    Both run the one fit driver (:mod:`pincal.identification.solvers._driver`) and end in the
    same finishing step.

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
    with _blas().limit(limits=1):  # small dense solves: threaded BLAS only adds contention
        return _run(problem, method, entry, opts, progress)


@functools.cache
def _blas() -> ThreadpoolController:
    """The BLAS libraries loaded (found once: the search costs ~1 ms per fit)."""
    return ThreadpoolController()


def _policy(problem: IdentificationProblem, model: CalibrationProblem) -> FitPolicy:
    """The driver's policy for one pose file: its base rule, the weak bound if declared."""
    bound = problem.weak_bound  # with the noise estimated, σ̂ of a far start holds everything
    declared = bound is not None and model.noise_source != "estimate"
    weak = WeakBound(*bound) if bound is not None and declared else None
    return FitPolicy(_base_rule(problem, model), weak, weighting=True)


def fitted_at_start(problem: IdentificationProblem) -> int | None:
    """How many parameters :func:`identify` of one pose file fits, known without solving.

    The count of the base set decided at ``problem.x0`` (less what a declared noise's
    weak bound holds there); None when it is known only after solving (the weak bound
    is checked again at the solution) or for a joint fit.
    """
    if problem.joint:
        return None
    model = problem.model
    with _blas().limit(limits=1):
        return fitted_machine_count(model, problem.x0, _policy(problem, model))


def _run(
    problem: IdentificationProblem,
    method: str,
    entry: Solver,
    opts: SolverOptions,
    progress: Progress,
) -> IdentificationResult:
    """The body of :func:`identify` (checked arguments), one BLAS thread."""
    model, x0 = problem.model, problem.x0
    policy = _policy(problem, model)
    d = drive(model, x0, entry, opts, policy, progress)
    raw0 = d.raw0
    assert isinstance(raw0, np.ndarray)  # one pose file: (m, k)
    local = opts if isinstance(opts, (GaussNewtonOptions, LMOptions)) else None
    prior = local.prior_weights(x0.size) if local is not None else None
    comps = tuple(problem.pose_file.components)
    result, _ = finish(
        d.model, d.settled, method=method, params=problem.params, raw0=raw0,
        stats=lambda raw: ResidualStats.from_residuals(raw, comps), residuals=d.settled.raw,
        initial_values=x0, prefix=d.fit_set.note + _held_note(problem.params, d.weak, policy.weak),
        prior=prior,
        identifiability=d.fit_set.identifiability, weighting=d.weighting,
        initial_residuals=raw0, components=comps,
    )  # fmt: skip
    if policy.weak is not None:
        held = [problem.params.names[i] for i in d.weak]
        result = with_held(result, held, f"placed beyond {policy.weak.describe()} by the poses")
    return result


def _held_note(params: ParameterSet, held: np.ndarray, bound: WeakBound | None) -> str:
    """The parameters the weak bound held, in words ("" when none)."""
    if bound is None or held.size == 0:
        return ""
    names = ", ".join(params.names[i] for i in held)
    return f"seen too weakly to place within {bound.describe()}, held at nominal: {names}; "
