"""What a registered solver hands back to :func:`pincal.identification.identify`."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from pincal.identification.results._result import SolverExtras

__all__ = ["Progress", "SolverOutcome"]

#: optional callback ``(iteration, cost)``
Progress = Callable[[int, float], None] | None


@dataclass(frozen=True)
class SolverOutcome:
    """Raw outcome of one solver run (the common post-processing makes the result).

    Attributes:
        x: (n,) parameter values [SI]; entries outside ``free`` equal the start values.
        iterations: solver iterations (evaluations for ``lm``).
        history: 0.5·‖whitened residual‖² per iteration.
        success: whether the solver reached its tolerance or the floor.
        message: solver message.
        extras: the solver's typed extras.
        fitted: indices of the parameters the solver actually fitted (None: all free).
    """

    x: np.ndarray
    iterations: int
    history: tuple[float, ...]
    success: bool
    message: str
    extras: SolverExtras | None = None
    fitted: np.ndarray | None = None
