"""The solvers of a fit.

How it is fitted: Gauss–Newton (robust losses included),
Levenberg–Marquardt, QPSO, step planning; the noise loop with variance components; the
driver that holds unidentifiable directions and the finish (covariance at the solution).
"""

from __future__ import annotations

from pincal.identification.solvers._driver import (
    FitPolicy,
    MarginalBound,
    drive,
    drive_holding,
    fitted_machine_count,
)
from pincal.identification.solvers._finish import finish
from pincal.identification.solvers._qpso import QPSOResult, qpso
from pincal.identification.solvers._qpso_identify import COST_MODELS, QPSOOptions
from pincal.identification.solvers._qpso_stepwise import (
    QPSOStage,
    QPSOStepwiseResult,
    qpso_stepwise,
)
from pincal.identification.solvers._solvers import METHODS, SOLVERS, Solver, SolverOptions, solver

__all__ = [
    "COST_MODELS",
    "METHODS",
    "SOLVERS",
    "FitPolicy",
    "MarginalBound",
    "QPSOOptions",
    "QPSOResult",
    "QPSOStage",
    "QPSOStepwiseResult",
    "Solver",
    "SolverOptions",
    "drive",
    "drive_holding",
    "finish",
    "fitted_machine_count",
    "qpso",
    "qpso_stepwise",
    "solver",
]
