"""The solver registry: name → (options dataclass, solve function).

Every solver takes the residual model, the start vector and the indices to fit, and
returns a :class:`pincal.identification.results._outcome.SolverOutcome`;
:func:`pincal.identification.identify` turns it into the one
:class:`pincal.identification.IdentificationResult`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

from pincal.errors import SolverOptionError
from pincal.identification._options import GaussNewtonOptions, LMOptions, StepPlanningOptions
from pincal.identification.results import SolverOutcome
from pincal.identification.solvers._levenberg_marquardt import levenberg_marquardt
from pincal.identification.solvers._local import gauss_newton
from pincal.identification.solvers._qpso_identify import QPSOOptions, qpso_search
from pincal.identification.solvers._step_planning import step_planning

__all__ = ["METHODS", "SOLVERS", "Solver", "SolverOptions", "solver"]

#: the options dataclass of a registered solver
SolverOptions = GaussNewtonOptions | LMOptions | QPSOOptions | StepPlanningOptions


@dataclass(frozen=True)
class Solver:
    """A registered identification solver.

    Attributes:
        name: registry name.
        options_type: its frozen options dataclass (validated on construction).
        solve: ``solve(problem_model, x0, free, options, progress) -> SolverOutcome``.
        summary: one line for help texts.
    """

    name: str
    options_type: type[SolverOptions]
    solve: Callable[..., SolverOutcome]
    summary: str

    def check_options(self, options: object | None) -> SolverOptions:
        """The options to use: defaults for None; a foreign type is refused.

        Raises:
            SolverOptionError: options of another solver's type.
        """
        if options is None:
            return self.options_type()
        if not isinstance(options, self.options_type):
            raise SolverOptionError(
                f"method {self.name!r} takes {self.options_type.__name__}, got "
                f"{type(options).__name__}"
            )
        return options


SOLVERS: dict[str, Solver] = {
    s.name: s
    for s in (
        Solver(
            "gauss-newton",
            GaussNewtonOptions,
            gauss_newton,
            "Gauss–Newton: bent (second-order) steps, Levenberg damping, then lm",
        ),
        Solver("lm", LMOptions, levenberg_marquardt, "scipy least_squares (robust losses)"),
        Solver(
            "qpso",
            QPSOOptions,
            partial(qpso_search, stepwise=False),
            "quantum-behaved particle swarm (seed 003)",
        ),
        Solver(
            "qpso-stepwise",
            QPSOOptions,
            partial(qpso_search, stepwise=True),
            "step-wise QPSO: one parameter at a time, then all (seed 003)",
        ),
        Solver(
            "step-planned",
            StepPlanningOptions,
            step_planning,
            "sensitivity-planned damped steps (seed 002)",
        ),
    )
}
#: registered solver names
METHODS = tuple(SOLVERS)


def solver(name: str) -> Solver:
    """The registered solver ``name``.

    Raises:
        SolverOptionError: unknown name (the message lists the registered ones).
    """
    try:
        return SOLVERS[name]
    except (KeyError, TypeError):
        raise SolverOptionError(
            f"unknown identification method {name!r}; choose from {METHODS}"
        ) from None
