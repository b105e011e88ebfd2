"""The prior of a marker calibration, chosen (or checked) by cross-validation.

A fitting procedure ``procedure(prior)`` (measurements → calibrated mechanism) is
cross-validated for each prior of the grid on the same folds; the prior of the lowest
held-out RMS is chosen (:func:`choose_prior`). The held-out error of a calibration whose
prior was chosen so is that of the whole procedure, choice included
(:func:`nested_choice`, cross-validated: nested CV); a fixed prior is cross-validated
alone (:func:`cross_validated`). A campaign of few poses leaves an outer fold's training
poses too few for the inner K-fold split (a 17-pose TIAGo session: 10 training poses of
an inner fold cannot fit the arm); that fold's prior is then chosen by leave-one-out,
which keeps all but one of its poses in each fit (:class:`NestedChoice`).

With orientation measured (a 6-D marker body) the candidates are compared by their
held-out squared errors whitened by each block's noise σ
(:meth:`pincal.validation.CrossValidation.squared_errors`), the σ those of the
weakest prior's fold fits (:meth:`pincal.validation.CrossValidation.fit_scales`:
what the poses given leave when the prior barely acts), so a prior that helps the
positions and harms the orientation by more is not chosen.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from pincal.errors import TooFewPosesError
from pincal.identification import Prior
from pincal.measure import Measurements
from pincal.model import Mechanism
from pincal.validation import BlockScales, CrossValidation, cross_validate
from pincal.workflow._marker_settings import PRIOR_GRID
from pincal.workflow._registrations import MarkerData, MarkerProcedure

__all__ = ["NestedChoice", "PriorChoice", "choose_prior", "cross_validated", "nested_choice"]

#: measurements → calibrated mechanism, for one prior
Procedure = Callable[[Prior | None], MarkerProcedure]


@dataclass(frozen=True)
class PriorChoice:
    """A prior with the held-out error of the procedure that uses it.

    Attributes:
        prior: the prior (None: no prior).
        cv: the cross-validation of the procedure with ``prior`` (for a chosen prior,
            on the folds that chose it: the lowest of the table, optimistic).
        table: when chosen, every candidate's (σ [mm, mrad], held-out RMS [mm]), in the
            order tried; empty for a prior that was given.
        orientation: when chosen with orientation measured, every candidate's held-out
            RMS rotation angle [mrad] (the order of ``table``), else empty.
        scales: the σ that whitened the choice (orientation measured), else None.
    """

    prior: Prior | None
    cv: CrossValidation
    table: tuple[tuple[float, float], ...] = ()
    orientation: tuple[float, ...] = ()
    scales: BlockScales | None = None

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
    """The prior of ``grid`` (σ in mm and mrad) of the lowest K-fold held-out error.

    The error is the RMS position error, or with orientation measured the mean
    whitened squared error (see the module). Ties keep the stronger prior (the one
    tried first).
    """
    priors = [Prior(s * 1e-3, s * 1e-3) for s in grid]
    cvs = []
    for s, prior in zip(grid, priors, strict=True):
        cvs.append(cross_validate(procedure(prior), meas, k, seed))
        if progress is not None:
            progress(f"prior σ {s:g} mm / {s:g} mrad: held-out RMS {cvs[-1].rms * 1e3:.3f} mm")
    assert cvs, "an empty prior grid"
    scales = cvs[-1].fit_scales()
    if scales is None:
        score = [cv.rms for cv in cvs]
    else:
        score = [float(np.mean(cv.squared_errors(scales))) for cv in cvs]
    best = min(range(len(cvs)), key=lambda i: (score[i], i))
    table = tuple((float(s), cv.rms * 1e3) for s, cv in zip(grid, cvs, strict=True))
    turned = tuple(float(cv.orientation_rms) * 1e3 for cv in cvs if cv.orientation_rms is not None)
    return PriorChoice(priors[best], cvs[best], table, turned, scales)


class NestedChoice:
    """Measurements → calibrated mechanism with the prior chosen on those measurements.

    Cross-validating it is nested cross-validation: each outer fold chooses its prior by
    an inner K-fold CV of its own training poses, so no held-out pose takes part in
    choosing the prior that predicts it. When an inner fold's training poses are too
    few to fit (:class:`pincal.errors.TooFewPosesError`), the prior of those poses is
    chosen by leave-one-out instead (K = their number).

    Attributes:
        leave_one_out: the number of poses of every call whose prior was chosen by
            leave-one-out, in call order (empty when the K-fold split always fitted).
    """

    def __init__(self, procedure: Procedure, k: int, seed: int) -> None:
        self.procedure, self.k, self.seed = procedure, k, seed
        self.leave_one_out: list[int] = []

    def choose(self, parts: Sequence[Measurements]) -> PriorChoice:
        """The prior of ``parts`` (one set per marker): K-fold, else leave-one-out.

        Raises:
            TooFewPosesError: even leave-one-out leaves too few poses to fit.
        """
        try:
            return choose_prior(self.procedure, parts, self.k, self.seed)
        except TooFewPosesError as e:
            m = len(parts[0])
            if m <= self.k:
                raise
            try:
                choice = choose_prior(self.procedure, parts, m, self.seed)
            except TooFewPosesError as again:
                raise TooFewPosesError(
                    f"{m} poses cannot choose the prior: neither {self.k}-fold nor "
                    f"leave-one-out cross-validation leaves enough poses to fit ({again}); "
                    "measure more poses or give the prior (--prior LEN_MM,ANG_MRAD)"
                ) from e
            self.leave_one_out.append(m)
            return choice

    def __call__(self, meas: MarkerData) -> Mechanism:
        parts = (meas,) if isinstance(meas, Measurements) else tuple(meas)
        return self.procedure(self.choose(parts).prior)(meas)


def nested_choice(procedure: Procedure, k: int, seed: int) -> NestedChoice:
    """Measurements → calibrated mechanism with the prior chosen on those measurements.

    See :class:`NestedChoice` (the inner K-fold choice, leave-one-out when the poses of
    an outer fold are too few for it).
    """
    return NestedChoice(procedure, k, seed)
