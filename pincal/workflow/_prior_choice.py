"""The prior of a marker calibration, chosen (or checked) by cross-validation.

A prior's strength is chosen among :data:`PRIOR_GRID` by K-fold cross-validation of the
fit on the poses given (:class:`PriorChooser`): each candidate is fitted once on all of
them, and its K-fold held-out error is that fit's one-step leave-fold-out
(:func:`pincal.validation.linearised_cross_validation`: the fitted set, weights and
prior kept; exact for a linear model) — one fit per candidate instead of K. The
candidate of the lowest held-out error is chosen and its fit is the calibration.

The held-out error of a calibration whose prior was chosen so is that of the whole
procedure, choice included: cross-validating a :class:`PriorChooser` (real refits of
every outer fold, each choosing its prior on its own training poses) is nested
cross-validation, and that is the figure a calibration reports. A fixed prior is
cross-validated by real refits alone (:func:`cross_validated`).

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

from pincal.identification import MarkerFit, Prior, linearise_marker_fit
from pincal.measure import MarkerSetup, Measurements
from pincal.model import Mechanism
from pincal.validation import (
    BlockScales,
    CrossValidation,
    cross_validate,
    kfold,
    linearised_cross_validation,
)
from pincal.workflow._marker_settings import PRIOR_GRID
from pincal.workflow._registrations import MarkerData

__all__ = ["Fitter", "PriorChoice", "PriorChooser", "cross_validated", "pick_prior"]

#: prior → (measurements → the marker fit with that prior)
Fitter = Callable[[Prior | None], Callable[[MarkerData], MarkerFit]]


@dataclass(frozen=True)
class PriorChoice:
    """A prior with the held-out error of the procedure that uses it.

    Attributes:
        prior: the prior (None: no prior).
        cv: the cross-validation of the fit with ``prior``: for a given prior by real
            refits; for a chosen one the linearised leave-fold-out that chose it (the
            lowest of the table, optimistic).
        table: when chosen, every candidate's (σ [mm, mrad], held-out RMS [mm]), in the
            order tried; empty for a prior that was given.
        orientation: when chosen with orientation measured, every candidate's held-out
            RMS rotation angle [mrad] (the order of ``table``), else empty.
        scales: the σ that whitened the choice (orientation measured), else None.
        fit: when chosen, the fit with ``prior`` on the poses that chose it.
    """

    prior: Prior | None
    cv: CrossValidation
    table: tuple[tuple[float, float], ...] = ()
    orientation: tuple[float, ...] = ()
    scales: BlockScales | None = None
    fit: MarkerFit | None = None

    @property
    def chosen(self) -> bool:
        """True when the prior was chosen by cross-validation (a table of candidates exists)."""
        return bool(self.table)


def cross_validated(
    fitter: Fitter, prior: Prior | None, meas: Sequence[Measurements], k: int, seed: int
) -> PriorChoice:
    """A given prior, cross-validated by refitting each of K folds (from ``seed``)."""
    fit = fitter(prior)
    return PriorChoice(prior, cross_validate(lambda d: fit(d).calibrated, meas, k, seed))


def pick_prior(
    grid: Sequence[float],
    cvs: Sequence[CrossValidation],
    fits: Sequence[MarkerFit] | None = None,
) -> PriorChoice:
    """The candidate of ``grid`` (σ in mm and mrad) of the lowest held-out error.

    ``cvs`` holds each candidate's cross-validation, ``fits`` (optional) its fit. The
    error is the RMS position error, or with orientation measured the mean whitened
    squared error (see the module). Ties keep the stronger prior (the one tried first).
    """
    assert cvs and len(cvs) == len(grid), "one cross-validation per candidate"
    scales = cvs[-1].fit_scales()
    if scales is None:
        score = [cv.rms for cv in cvs]
    else:
        score = [float(np.mean(cv.squared_errors(scales))) for cv in cvs]
    best = min(range(len(cvs)), key=lambda i: (score[i], i))
    table = tuple((float(s), cv.rms * 1e3) for s, cv in zip(grid, cvs, strict=True))
    turned = tuple(float(cv.orientation_rms) * 1e3 for cv in cvs if cv.orientation_rms is not None)
    s = grid[best] * 1e-3
    fit = None if fits is None else fits[best]
    return PriorChoice(Prior(s, s), cvs[best], table, turned, scales, fit)


class PriorChooser:
    """Measurements → calibrated mechanism with the prior chosen on those measurements.

    Each candidate of ``grid`` is fitted on the measurements given and judged by its
    linearised K-fold leave-fold-out (see the module); cross-validating a chooser is
    nested cross-validation, no held-out pose taking part in choosing the prior that
    predicts it.

    Args:
        fitter: prior → (measurements → marker fit).
        setup: the marker set-up the fits use (several markers: one set each).
        k: folds of the choice; seed: their seed.
        grid: candidate σ [mm for lengths, mrad for angles], strongest first.
        progress: called with a line per candidate, or None.
    """

    def __init__(
        self,
        fitter: Fitter,
        setup: MarkerSetup,
        k: int,
        seed: int,
        grid: Sequence[float] = PRIOR_GRID,
        progress: Callable[[str], None] | None = None,
    ) -> None:
        self.fitter, self.setup, self.k, self.seed = fitter, setup, k, seed
        self.grid, self.progress = tuple(grid), progress

    def choose(self, meas: MarkerData) -> PriorChoice:
        """The prior of ``meas`` (one set, or one per marker) and its fit."""
        parts = (meas,) if isinstance(meas, Measurements) else tuple(meas)
        folds = kfold(len(parts[0]), self.k, self.seed)
        fits, cvs = [], []
        for s in self.grid:
            fits.append(self.fitter(Prior(s * 1e-3, s * 1e-3))(meas))
            lin = linearise_marker_fit(fits[-1], self.setup, meas)
            cvs.append(linearised_cross_validation(lin, folds))
            if self.progress is not None:
                self.progress(f"prior σ {s:g} mm / {s:g} mrad: held-out RMS "
                              f"{cvs[-1].rms * 1e3:.3f} mm (linearised)")  # fmt: skip
        return pick_prior(self.grid, cvs, fits)

    def __call__(self, meas: MarkerData) -> Mechanism:
        fit = self.choose(meas).fit
        assert fit is not None
        return fit.calibrated
