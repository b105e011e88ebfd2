"""The prior of a marker calibration, chosen (or checked) by cross-validation.

A fitting procedure ``procedure(prior)`` (measurements → calibrated mechanism) is
cross-validated for each prior of the grid on the same folds; the prior of the lowest
held-out RMS is chosen (:func:`choose_prior`). The held-out error of a calibration whose
prior was chosen so is that of the whole procedure, choice included
(:func:`nested_choice`, cross-validated: nested CV); a fixed prior is cross-validated
alone (:func:`cross_validated`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from pincal.identification import CrossValidation, Prior, cross_validate
from pincal.measure import Measurements
from pincal.model import Mechanism
from pincal.workflow._marker_settings import PRIOR_GRID

__all__ = ["PriorChoice", "choose_prior", "cross_validated", "nested_choice"]

#: measurements → calibrated mechanism, for one prior
Procedure = Callable[[Prior | None], Callable[[Any], Mechanism]]


@dataclass(frozen=True)
class PriorChoice:
    """A prior with the held-out error of the procedure that uses it.

    Attributes:
        prior: the prior (None: no prior).
        cv: the cross-validation of the procedure with ``prior`` (for a chosen prior,
            on the folds that chose it: the lowest of the table, optimistic).
        table: when chosen, every candidate's (σ [mm, mrad], held-out RMS [mm]), in the
            order tried; empty for a prior that was given.
    """

    prior: Prior | None
    cv: CrossValidation
    table: tuple[tuple[float, float], ...] = ()

    @property
    def chosen(self) -> bool:
        """True when the prior was chosen by cross-validation (a table of candidates exists)."""
        return bool(self.table)


def cross_validated(
    procedure: Procedure, prior: Prior | None, meas: Sequence[Measurements], k: int, seed: int
) -> PriorChoice:
    """A given prior, cross-validated (K folds from ``seed``)."""
    return PriorChoice(prior, cross_validate(procedure(prior), meas, k, seed))


def choose_prior(
    procedure: Procedure,
    meas: Sequence[Measurements],
    k: int,
    seed: int,
    grid: Sequence[float] = PRIOR_GRID,
    progress: Callable[[str], None] | None = None,
) -> PriorChoice:
    """The prior of ``grid`` (σ in mm and mrad) of the lowest K-fold held-out RMS.

    Ties keep the stronger prior (the one tried first).
    """
    best: tuple[float, PriorChoice | None] = (math.inf, None)
    table: list[tuple[float, float]] = []
    for s in grid:
        prior = Prior(s * 1e-3, s * 1e-3)
        cv = cross_validate(procedure(prior), meas, k, seed)
        table.append((float(s), cv.rms * 1e3))
        if progress is not None:
            progress(f"prior σ {s:g} mm / {s:g} mrad: held-out RMS {cv.rms * 1e3:.3f} mm")
        if cv.rms < best[0]:
            best = (cv.rms, PriorChoice(prior, cv))
    assert best[1] is not None, "an empty prior grid"
    return PriorChoice(best[1].prior, best[1].cv, tuple(table))


def nested_choice(procedure: Procedure, k: int, seed: int) -> Callable[[Any], Mechanism]:
    """Measurements → calibrated mechanism with the prior chosen on those measurements.

    Cross-validating this procedure is nested cross-validation: each outer fold chooses
    its prior by an inner K-fold CV of its own training poses, so no held-out pose
    takes part in choosing the prior that predicts it.
    """

    def fit(meas: Any) -> Mechanism:
        parts = (meas,) if isinstance(meas, Measurements) else tuple(meas)
        return procedure(choose_prior(procedure, parts, k, seed).prior)(meas)

    return fit
