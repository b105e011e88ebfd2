"""Which unknowns a fit solves for: the set-decision rules the driver takes as inputs.

Every fit starts from the identifiable base set of what it may fit, decided from the
whitened Jacobian at the start values. Two rules exist:

- :class:`StructuralBase` (a pose file): the base set of the candidates from the
  model's structural Jacobian, without the parameters that break loop closure and the
  translations inside emulated ball or universal joints (both masks are inputs);
  ``reduce=False`` refuses a rank-deficient set instead.
- :class:`JointBase` (several data sets): the base set over every unknown, the data
  sets' own unknowns entering first, so what an instrument absorbs is held on the
  machine side.

:class:`WeakBound` is the third input: hold the base-set directions the data place only
beyond a bound (k σ at the declared noise), and check again at the solution.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pincal.errors import TooFewPosesError, UnidentifiableError
from pincal.identification.problem._gauge import null_motions, weak_parameters
from pincal.identification.problem._instrument_problem import InstrumentProblem
from pincal.identification.problem._problem import CalibrationProblem
from pincal.identification.problem._residual_model import ResidualModel
from pincal.sensitivity import (
    Identifiability,
    analyse_jacobian,
    closure_loops,
    placement_words,
)

__all__ = ["BaseRule", "FitSet", "JointBase", "StructuralBase", "WeakBound"]


@dataclass(frozen=True)
class FitSet:
    """The unknowns a fit solves for, decided at the start.

    Attributes:
        free: (f,) sorted indices into the model's unknowns.
        identifiability: the analysis the decision came from (recorded with the result).
        note: what was held and why, in words ("" when nothing was).
        gauge: the motions the data do not observe (held at nominal), in words.
    """

    free: np.ndarray
    identifiability: Identifiability
    note: str = ""
    gauge: tuple[str, ...] = ()


@dataclass(frozen=True)
class StructuralBase:
    """The identifiable base set of ``candidates`` from the structural Jacobian.

    Attributes:
        candidates: (p,) indices of the parameters the caller asks to fit.
        breaks_closure: (n,) True for parameters that break loop closure (held).
        splits_joint: (n,) True for translations inside emulated joints (held).
        reduce: fit the base set of a rank-deficient set (False: refuse it).
        n_poses: poses measured (for the too-few-poses message).
    """

    candidates: np.ndarray
    breaks_closure: np.ndarray
    splits_joint: np.ndarray
    reduce: bool
    n_poses: int

    def decide(self, model: ResidualModel, x0: np.ndarray, J0: np.ndarray) -> FitSet:
        """The fitted set at ``x0`` (``J0`` unused: the structural Jacobian decides).

        Raises:
            TooFewPosesError: every equation is used up before the set is identifiable.
            UnidentifiableError: rank-deficient and ``reduce`` is False.
        """
        assert isinstance(model, CalibrationProblem)
        names, units = model.names, model.units
        candidates, breaking, splitting = self.candidates, self.breaks_closure, self.splits_joint
        Js = model.structural_jacobian(x0)  # not the measured deviation's mixing
        loops = closure_loops(model.mech, model.params) if breaking.any() else ()
        ident = analyse_jacobian(Js, names, breaks_closure=breaking, splits_joint=splitting,
                                 units=units, loops=loops)  # fmt: skip
        if np.array_equal(candidates, np.arange(len(names))):
            sub = ident  # fitting every parameter: the same analysis
        else:
            sub = analyse_jacobian(
                Js[:, candidates],
                tuple(names[i] for i in candidates),
                breaks_closure=breaking[candidates],
                splits_joint=splitting[candidates],
            )
        n, n_eq = candidates.size, model.n_equations
        if sub.rank < n and sub.rank >= n_eq:
            rows = len(model.rows)
            raise TooFewPosesError(
                f"{self.n_poses} poses × {rows} components = {n_eq} equations for "
                f"{n} parameters, and all {n_eq} are used up (rank {sub.rank}): the data "
                f"cannot tell which parameters are identifiable; measure at least "
                f"{-(-n // rows)} poses"
            )
        if sub.full_rank:
            return FitSet(candidates, ident)
        if not self.reduce:
            raise UnidentifiableError(
                f"only {sub.rank} of {n} parameters are identifiable from these poses:\n"
                + "\n".join(sub.describe()),
                sub.unidentifiable_names,
            )
        free = candidates[sub.base]
        held = np.setdiff1d(candidates, free)
        n_break = int(np.isin(held, ident.breaks_closure).sum())
        n_split = int(np.isin(held, ident.splits_joint).sum())
        why = [f"{n_break} break loop closure"] if n_break else []
        why += [f"{n_split} would split an emulated ball or universal joint"] if n_split else []
        note = (
            f"identified the {free.size} base parameters; held {n - free.size} "
            f"unidentifiable ones at their initial values"
            + (f" ({'; '.join(why)})" if why else "")
            + ". "
        )
        return FitSet(free, ident, note)


@dataclass(frozen=True)
class JointBase:
    """The identifiable base set of a joint model over every unknown, own unknowns first.

    What the base leaves out is named as motions of machine and instruments the data
    do not observe (:func:`pincal.identification.problem._gauge.null_motions`), in ``gauge``.
    """

    def decide(self, model: ResidualModel, x0: np.ndarray, J0: np.ndarray) -> FitSet:
        """The fitted set: the base of the whitened Jacobian ``J0`` at ``x0``, sorted."""
        assert isinstance(model, InstrumentProblem)
        names, order, n = model.names, model.order, model.n_machine
        ident = analyse_jacobian(J0[:, order], tuple(names[i] for i in order))
        P0, Jp0 = model.tool_points(x0)
        motions = null_motions(J0, Jp0, P0, n, ident, order, names[n:])
        return FitSet(np.sort(order[ident.base]), ident, gauge=tuple(motions.lines()))


#: the base-set rules the driver takes
BaseRule = StructuralBase | JointBase


@dataclass(frozen=True)
class WeakBound:
    """Hold base-set directions the data place only beyond a bound.

    Attributes:
        length: largest plausible k σ of a length unknown [m].
        angle: largest plausible k σ of an angle unknown [rad].
        sigmas: k, how many σ the bound is of.
        at_solution: check again with the solution's Jacobian and refit when it sees
            weaker directions than the start did.
    """

    length: float
    angle: float
    sigmas: float = 1.0
    at_solution: bool = True

    def held(self, Jw: np.ndarray, free: np.ndarray, units: tuple[str, ...], n: int) -> np.ndarray:
        """Indices (sorted, a subset of ``free``) held (see :func:`weak_parameters`).

        Args:
            Jw: (N, p) whitened Jacobian.
            free: indices into its columns fitted so far.
            units: per column ``"m"`` or ``"rad"``.
            n: the machine's unknowns (columns below n, held first).
        """
        bounds = (self.length / self.sigmas, self.angle / self.sigmas)
        return weak_parameters(Jw, free, units, n, bounds)

    def describe(self) -> str:
        """The bound in words."""
        if self.sigmas == 1.0:
            return placement_words((self.length, self.angle))
        return f"{self.length * 1e3:g} mm / {self.angle:g} rad ({self.sigmas:g}σ)"
