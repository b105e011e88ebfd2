"""One driver for every fit: start → fitted set → solve → settle → re-decide → settled fit.

:func:`drive` runs the sequence every identification shares over any
:class:`pincal.identification.problem._residual_model.ResidualModel`:

1. evaluate the model at the start values (and, when the noise is estimated, weigh its
   blocks by their start residuals: :func:`pincal.identification.solvers._noise.initial_weights`);
2. decide the fitted set by the base-set rule given (:class:`StructuralBase` for a pose
   file, :class:`JointBase` for several data sets), then hold what a
   :class:`WeakBound` names;
3. solve with the registered solver (Gauss–Newton or Levenberg–Marquardt with their
   robust losses and prior; a global search), re-weighting by variance components when
   the policy says so (:func:`pincal.identification.solvers._noise.weighted_fit`);
4. settle at the answer (:func:`pincal.identification.solvers._finish.settle`);
5. with a weak bound checked at the solution, hold what the solution's Jacobian sees
   more weakly still and solve again from the start.

The caller turns the :class:`Driven` fit into its result with
:func:`pincal.identification.solvers._finish.finish`. The policies are typed inputs
(:class:`FitPolicy`); the driver has no knowledge of which route calls it.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from pincal.identification._weighting import Weighting
from pincal.identification.problem import (
    BaseRule,
    CalibrationProblem,
    FitSet,
    RawResiduals,
    ResidualModel,
    WeakBound,
)
from pincal.identification.results import IdentificationResult, Progress
from pincal.identification.solvers._finish import Settled, settle
from pincal.identification.solvers._noise import initial_weights, weighted_fit
from pincal.identification.solvers._solvers import Solver, SolverOptions

__all__ = [
    "Driven",
    "FitPolicy",
    "MarginalBound",
    "Refitted",
    "Start",
    "drive",
    "drive_holding",
    "fitted_machine_count",
    "start",
]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class FitPolicy:
    """How :func:`drive` decides what to fit and how it weighs the data.

    Attributes:
        base: the identifiable base-set rule at the start.
        weak: hold the directions placed only beyond this bound (None: none held).
        weighting: weigh by variance components when the noise is not declared and
            report the :class:`Weighting` (a pose-file model: declared noise is used
            as it is, an undeclared one estimated); False solves once as whitened.
        noise_floor: accept an unconverged stop at the kinematic precision of the cost
            (see :func:`pincal.identification.solvers._finish.settle`).
    """

    base: BaseRule
    weak: WeakBound | None = None
    weighting: bool = False
    noise_floor: bool = False


@dataclass(frozen=True)
class Driven:
    """A fit run by :func:`drive`, settled at its answer.

    Attributes:
        model: the residual model at the end (re-weighted when the noise was estimated).
        settled: the model evaluated at the solver's answer.
        fit_set: the set decided at the start (base set, its analysis, what it held).
        free: (f,) indices fitted (``fit_set.free`` less ``weak``).
        weak: (w,) indices held by the weak bound (at the start or at the solution).
        raw0: raw residuals at the start [m, rad].
        weighting: the noise used (``FitPolicy.weighting``), else None.
    """

    model: ResidualModel
    settled: Settled
    fit_set: FitSet
    free: np.ndarray
    weak: np.ndarray
    raw0: RawResiduals
    weighting: Weighting | None


def _solve(
    model: ResidualModel,
    entry: Solver,
    x0: np.ndarray,
    free: np.ndarray,
    opts: SolverOptions,
    progress: Progress,
    policy: FitPolicy,
) -> tuple[ResidualModel, Settled, Weighting | None]:
    weighting = None
    if policy.weighting:
        assert isinstance(model, CalibrationProblem)
        out, model, weighting = weighted_fit(model, entry, x0, free, opts, progress)
    else:
        out = entry.solve(model, x0, free, opts, progress)
    return model, settle(model, out, free, noise_floor=policy.noise_floor), weighting


@dataclass(frozen=True)
class Start:
    """A fit at its start values, before solving (steps 1–2 of :func:`drive`).

    Attributes:
        model: the residual model, weighed by its start residuals when the noise is
            estimated.
        raw0: raw residuals at the start [m, rad].
        fit_set: the set decided by the base-set rule.
        free: (f,) indices to fit (``fit_set.free`` less ``weak``).
        weak: (w,) indices held by the weak bound at the start.
    """

    model: ResidualModel
    raw0: RawResiduals
    fit_set: FitSet
    free: np.ndarray
    weak: np.ndarray


def start(model: ResidualModel, x0: np.ndarray, policy: FitPolicy) -> Start:
    """Evaluate ``model`` at ``x0`` [SI], weigh it and decide the fitted set (no solve).

    Raises:
        TooFewPosesError, UnidentifiableError: from the base-set rule.
    """
    _, J0, raw0 = model.evaluate(x0)
    if policy.weighting:
        assert isinstance(model, CalibrationProblem) and isinstance(raw0, np.ndarray)
        model, J0 = initial_weights(model, J0, raw0)
    fit_set = policy.base.decide(model, x0, J0)
    free, weak = fit_set.free, np.zeros(0, dtype=int)
    if policy.weak is not None:
        weak = policy.weak.held(J0, free, model.units, model.n_machine)
        free = np.setdiff1d(free, weak)
    return Start(model, raw0, fit_set, free, weak)


def fitted_machine_count(model: ResidualModel, x0: np.ndarray, policy: FitPolicy) -> int | None:
    """How many machine unknowns a :func:`drive` of ``model`` from ``x0`` fits.

    Known before solving unless a weak bound is checked again at the solution (then
    None: only the solve tells).
    """
    if policy.weak is not None and policy.weak.at_solution:
        return None
    return int(np.sum(start(model, x0, policy).free < model.n_machine))


def drive(
    model: ResidualModel,
    x0: np.ndarray,
    entry: Solver,
    opts: SolverOptions,
    policy: FitPolicy,
    progress: Progress = None,
) -> Driven:
    """Run one fit of ``model`` from ``x0`` (see the module docstring).

    Args:
        model: the residual model.
        x0: (n_x,) start values [SI].
        entry: the registered solver (:func:`pincal.identification.solvers._solvers.solver`).
        opts: its checked options.
        policy: the set-decision and weighting policies.
        progress: optional ``(iteration, cost)`` callback passed to the solver.

    Raises:
        TooFewPosesError, UnidentifiableError: from the base-set rule.
        NoiseEstimationError: too few redundant equations to estimate the noise.
    """
    begun = start(model, x0, policy)
    fit_set, free, weak = begun.fit_set, begun.free, begun.weak
    if fit_set.note:
        log.info(fit_set.note)
    model, settled, weighting = _solve(begun.model, entry, x0, free, opts, progress, policy)
    if policy.weak is not None and policy.weak.at_solution:
        f = settled.fitted  # the solution's Jacobian may see a direction weaker still
        units = tuple(model.units[i] for i in f)
        more = f[policy.weak.held(settled.Jf, np.arange(f.size), units,
                                  int(np.sum(f < model.n_machine)))]  # fmt: skip
        if more.size:
            weak, free = np.union1d(weak, more), np.setdiff1d(free, more)
            model, settled, weighting = _solve(
                begun.model, entry, x0, free, opts, progress, policy
            )
    return Driven(model, settled, fit_set, free, weak, begun.raw0, weighting)


@dataclass(frozen=True)
class MarginalBound:
    """Hold machine parameters whose k σ, as a finished fit states it, exceeds a bound.

    Unlike :class:`WeakBound` (directions of the whitened Jacobian at the declared
    noise, inside one fit), this bound is on the marginal σ of the finished fit — prior
    and estimated noise included — so each hold ends a fit and starts the next.

    Attributes:
        length: largest plausible k σ of a length parameter [m].
        angle: largest plausible k σ of an angle parameter [rad].
        sigmas: k.
        rounds: largest number of fits (each holds at least one more parameter).
    """

    length: float
    angle: float
    sigmas: float = 2.0
    rounds: int = 6

    def describe(self) -> str:
        """The bound in words, e.g. ``20 mm / 0.1 rad (2σ)``."""
        return f"{self.length * 1e3:g} mm / {self.angle:g} rad ({self.sigmas:g}σ)"

    def weak(
        self, result: IdentificationResult, exempt: Callable[[str], bool]
    ) -> list[tuple[str, str]]:
        """Identified parameters beyond the bound (NaN counts), with their k σ in words."""
        weak = []
        for k, i in enumerate(np.flatnonzero(result.identified)):  # std: identified only
            name, unit = result.names[i], result.units[i]
            ks = self.sigmas * float(result.std[k])
            if not exempt(name) and not ks <= (self.length if unit == "m" else self.angle):
                weak.append((name, f"{self.sigmas:g}σ {_amount(ks, unit)}"))
        return weak


@dataclass(frozen=True)
class Refitted:
    """The outcome of :func:`drive_holding`.

    Attributes:
        result: the last accepted fit.
        method: the solver that produced it.
        notes: what the guards did, in words (switches, holds, the set re-decided).
        held: the parameters held by the bound, in order.
    """

    result: IdentificationResult
    method: str
    notes: tuple[str, ...]
    held: tuple[str, ...]


#: one whole fit (through :func:`drive`): (names to fit, method, start values or None)
FitFunction = Callable[[list[str], str, np.ndarray | None], IdentificationResult]
#: (names to fit, start values) → parameters a fit from there identifies (None: unknown)
SetCount = Callable[[list[str], np.ndarray], int | None]


def _amount(value: float, unit: str) -> str:
    return f"{value * 1e3:.3g} {'mm' if unit == 'm' else 'mrad'}"


def drive_holding(
    fit: FitFunction,
    names: list[str],
    method: str,
    bound: MarginalBound,
    exempt: Callable[[str], bool],
    counted: SetCount | None = None,
) -> Refitted:
    """Fit, hold what a :class:`MarginalBound` names and fit again; then re-decide.

    1. fit ``names`` with ``method``; Gauss–Newton that does not converge is replaced
       by Levenberg–Marquardt from the same start (and kept for the later fits);
    2. hold the parameters beyond ``bound`` (never those ``exempt`` names) at their
       start values and fit again, at most ``bound.rounds`` fits;
    3. decide the identifiable set again at the solution (the start can hide
       parameters) by a fit started there, kept when its set differs and it converged
       (or the last one did not).

    Args:
        fit: one whole fit, each a run of :func:`drive`.
        names: the parameters to fit at first.
        method: ``"gauss-newton"`` or ``"lm"``.
        bound: the bound on the finished fit's marginal σ.
        exempt: names never held (e.g. the instrument frame's).
        counted: how many parameters a fit of these names from these values would
            identify, without solving (None when unknown before solving): step 3 then
            solves only when the count differs (the result is the same).
    """
    notes: list[str] = []
    held: list[str] = []
    used = method
    for _ in range(bound.rounds):  # each round holds at least one more parameter, or stops
        result = fit(names, used, None)
        if not result.success and used == "gauss-newton":
            notes.append(
                f"Gauss–Newton did not converge ({result.message.strip()}); switched to "
                "Levenberg–Marquardt from the same start"
            )
            used = "lm"
            result = fit(names, used, None)
        weak = bound.weak(result, exempt)
        if not weak:
            break
        notes.append(
            f"held {len(weak)} machine parameters at their nominal values, their "
            f"{bound.sigmas:g}σ exceeding {_amount(bound.length, 'm')} / "
            f"{_amount(bound.angle, 'rad')} (the poses barely move those directions): "
            + ", ".join(f"{n} ({v})" for n, v in weak)
        )
        out = {n for n, _ in weak}
        held += [n for n, _ in weak]
        names = [n for n in names if n not in out]
    n0 = int(result.identified.sum())
    # a refit whose set has the size of this one's is not kept: skip it when its set
    # is known before solving
    if counted is None or counted(names, result.full_values) != n0:
        again = fit(names, used, result.full_values)
        n1 = int(again.identified.sum())
        if n1 != n0 and (again.success or not result.success):
            notes.append(
                f"the identifiable set decided again at the solution has {n1} parameters "
                f"(at the start {n0}); the fit was refined from the solution with that set"
            )
            result = again
    return Refitted(result, used, tuple(notes), tuple(held))
