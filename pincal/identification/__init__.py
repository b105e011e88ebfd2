"""Stage 5 — from measurements to parameters: Gauss–Newton, LM, QPSO, step-wise QPSO and
sensitivity-planned steps, with covariances at the Cramér–Rao bound.
"""

from __future__ import annotations

from pincal.identification._identify import (
    METHODS,
    CalibrationProblem,
    IdentificationResult,
    ResidualStats,
    identify,
)
from pincal.identification._qpso import (
    QPSOResult,
    QPSOStage,
    QPSOStepwiseResult,
    qpso,
    qpso_stepwise,
)
from pincal.identification._qpso_identify import (
    QPSOIdentification,
    QPSOOptions,
    qpso_identify,
)
from pincal.identification._step_planning import (
    StepPlanningResult,
    step_planned_identify,
)

__all__ = [
    "METHODS",
    "CalibrationProblem",
    "IdentificationResult",
    "QPSOIdentification",
    "QPSOOptions",
    "QPSOResult",
    "QPSOStage",
    "QPSOStepwiseResult",
    "ResidualStats",
    "StepPlanningResult",
    "identify",
    "qpso",
    "qpso_identify",
    "qpso_stepwise",
    "step_planned_identify",
]
