"""K-fold cross-validation of a fit from its linearisation (no refits).

:func:`linearised_cross_validation` gives the :class:`CrossValidation` of the same folds
as :func:`pincal.validation.cross_validate`, each fold's fit replaced by the one-step
leave-fold-out of :class:`pincal.identification.LinearisedFit` (exact for a linear
model, first order otherwise). It ranks candidates cheaply (a prior's strength:
:func:`pincal.workflow.choose_prior`); held-out errors that are reported come from
real refits.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from pincal.identification import LinearisedFit
from pincal.validation._cross_validation import CrossValidation

__all__ = ["linearised_cross_validation"]


def _per_pose(fit: LinearisedFit, raw: np.ndarray, rotation: bool) -> np.ndarray:
    """(m,) per pose: the RMS over markers of the position error [m] (or the angle [rad]).

    With ``rotation``, the rotation error angle of the first marker's body.
    """
    m = int(fit.pose.max()) + 1
    rows = fit.component >= 3 if rotation else fit.component < 3
    if rotation:
        rows &= fit.marker == 0
    sq = np.zeros((int(fit.marker.max()) + 1, m))
    np.add.at(sq, (fit.marker[rows], fit.pose[rows]), raw[rows] ** 2)
    if rotation:
        return np.sqrt(sq[0])
    return np.sqrt(np.mean(sq, axis=0))


def linearised_cross_validation(fit: LinearisedFit, folds: Sequence[np.ndarray]) -> CrossValidation:
    """Held-out errors of ``fit``'s one-step leave-fold-out on ``folds`` (pose indices).

    Orientation errors are kept when the rows measure all three rotation components.
    """
    m = int(fit.pose.max()) + 1
    turned = set(np.unique(fit.component)) >= {3, 4, 5}
    held, fit_rms = np.empty(m), np.empty(len(folds))
    held_r, fit_r = (np.empty(m), np.empty(len(folds))) if turned else (None, None)
    for j, rows in enumerate(folds):
        raw = fit.without(rows)
        train = np.setdiff1d(np.arange(m), rows)
        e = _per_pose(fit, raw, rotation=False)
        held[rows], fit_rms[j] = e[rows], float(np.sqrt(np.mean(e[train] ** 2)))
        if held_r is not None and fit_r is not None:
            a = _per_pose(fit, raw, rotation=True)
            held_r[rows], fit_r[j] = a[rows], float(np.sqrt(np.mean(a[train] ** 2)))
    return CrossValidation(tuple(np.asarray(f) for f in folds), held, fit_rms, held_r, fit_r)
