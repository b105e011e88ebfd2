"""Instrument files through the quality gate of pose files (issue 25).

:func:`check_instrument_data` is the look before the fit: a unit check of the readings.
Every built-in kind reads a quantity that changes at most as fast as the tool point
moves (``|∂v/∂p| ≤ 1``: a distance, a deflection, a plane or axis coordinate), so the
readings of one id spread at most as much as the nominal tool points do, plus the
machine's errors and the noise; readings spread far more are in a smaller unit than
the file declares (mm written as m). A kind whose readings may change faster sets
``Instrument.unit_gradient = False`` and is not checked.

:func:`instrument_gate` judges the fit with :func:`pincal.identification.check_quality`:
solver success, χ² of the readings against the files' σ (p-value), parameter changes,
and the deletion outlier test on the whitened per-pose residuals and Jacobian, the poses
it names confirmed by a refit without them (:func:`refit_confirmation`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import numpy as np

from pincal.errors import PincalError
from pincal.identification._instrument_identify import InstrumentIdentification
from pincal.identification._verdict import GateLimits, QualityIssue, QualityVerdict
from pincal.identification._weighting import Weighting
from pincal.identification.gate._outliers import refit_outliers
from pincal.identification.gate._quality import ConfirmOutliers, check_quality
from pincal.identification.problem import TRIAL_FAILURES
from pincal.measure import InstrumentData
from pincal.model import Mechanism

__all__ = ["check_instrument_data", "instrument_gate"]

#: readings may spread beyond the tool points' spread by this much for machine errors [m]
_SLACK = 0.01


def check_instrument_data(
    mech: Mechanism,
    datasets: Sequence[Any],
    labels: Sequence[str] | None = None,
    limits: GateLimits | None = None,
) -> QualityVerdict:
    """The unit check of scalar readings before the fit.

    Args:
        mech: the nominal mechanism.
        datasets: the fit's datasets (the :class:`InstrumentData` ones are checked).
        labels: a name per dataset for the messages (default ``dataset i``).
        limits: thresholds (its ``scale_band``; default :class:`GateLimits`).

    Returns:
        QualityVerdict (``cause`` ``units`` when a file refuses).
    """
    lim = limits or GateLimits()
    issues: list[QualityIssue] = []
    for i, d in enumerate(datasets):
        if not isinstance(d, InstrumentData) or not getattr(d.instrument, "unit_gradient", True):
            continue
        name = labels[i] if labels is not None else f"dataset {i}"
        P = np.array([mech.frame_placement(q).translation
                      for q in mech.configurations(d.q_act)])  # fmt: skip
        reach = float(np.linalg.norm(np.ptp(P, axis=0)))
        ids = d.ids if d.ids is not None else np.zeros(len(d), dtype=int)
        spread = max(float(np.ptp(d.values[ids == j])) for j in np.unique(ids))
        bound = lim.scale_band * reach + _SLACK + 10 * d.instrument.std
        if spread > bound:
            issues.append(QualityIssue(
                "units", True,
                f"{name}: the {d.kind} readings spread {spread * 1e3:.4g} mm, the nominal tool "
                f"points only {reach * 1e3:.4g} mm ({spread / max(reach, 1e-12):.3g}×; a "
                f"reading changes at most as fast as the tool point moves)",
            ))  # fmt: skip
    if not issues:
        return QualityVerdict(limits=lim)
    return QualityVerdict(
        tuple(issues), "units",
        "the readings look like a smaller unit than the file declares (e.g. mm written as "
        "m): check the file's length_unit.", limits=lim,
    )  # fmt: skip


def instrument_gate(
    fit: InstrumentIdentification,
    data: QualityVerdict | None = None,
    limits: GateLimits | None = None,
    instrument: str | None = None,
    *,
    mech: Mechanism | None = None,
    datasets: Sequence[Any] | None = None,
    labels: Sequence[str] | None = None,
) -> QualityVerdict:
    """Judge a joint instrument fit as a pose fit is judged.

    The per-pose deletion outlier test runs when the fit has uniform per-pose blocks
    (:attr:`InstrumentIdentification.whitened`): every file a scalar instrument, or
    every file a socket file without known distances. With ``mech`` and ``datasets``
    (all scalar instrument files) the poses it names are confirmed by a refit without
    them (:func:`refit_confirmation`), as for pose files.

    Args:
        fit: the outcome of :func:`pincal.identification.identify_instruments`.
        data: the verdict of :func:`check_instrument_data` (its issues come first).
        limits: thresholds (default ``data``'s, else :class:`GateLimits`).
        instrument: an instrument profile name (judges estimated noise only: unused by
            files that declare their σ, kept for one call signature).
        mech: the nominal mechanism the fit started from.
        datasets: the fit's datasets.
        labels: their labels (as given to the fit).
    """
    lim = limits or (data.limits if data is not None else GateLimits())
    confirm = None
    if mech is not None and datasets is not None:
        confirm = refit_confirmation(fit, mech, datasets, labels, lim)
    result, jac = fit.result, None
    if fit.whitened is not None:
        jac, z = fit.whitened
        raw = np.concatenate(fit.residuals[: len(z)]) if fit.residuals else np.zeros((0, 1))
        if raw.shape == z.shape:
            w = Weighting("declared", whitened=z, redundancy={
                "instrument": 0.0 if result.joint is None else float(result.joint.redundancy)})
            result = dataclasses.replace(result, weighting=w, residuals=raw)
        else:
            jac = None
    return check_quality(result, data=data, limits=lim, scalar_instrument=True,
                         jacobian=jac, instrument=instrument, confirm=confirm)  # fmt: skip


def refit_confirmation(
    fit: InstrumentIdentification,
    mech: Mechanism,
    datasets: Sequence[Any],
    labels: Sequence[str] | None,
    limits: GateLimits,
) -> ConfirmOutliers | None:
    """The refit that confirms outlying readings, for :func:`check_quality`'s ``confirm``.

    ``confirm(named, risk, cap)`` leaves the named poses (indices over the datasets in
    order) out, refits machine and instruments as the fit was made (Gauss–Newton,
    directions beyond ``limits``' change bound held), and runs the deletion test again
    over *all* readings linearised at the refit, the named ones also judged against the
    scale of the others (:func:`pincal.identification.gate._outliers.refit_outliers`): a fit
    pulled by a gross reading does not point at good ones, and two bad readings that
    mask each other at the refit are still confirmed. It returns None (keep the first
    answer) when the refit fails or its unknowns differ (a plane left without contacts).
    None for datasets other than scalar instrument files.
    """
    from pincal.identification._instrument_identify import identify_instruments
    from pincal.identification.problem import InstrumentProblem

    if not datasets or not all(isinstance(d, InstrumentData) for d in datasets):
        return None
    params = fit.result.parameter_set
    if params is None:
        return None
    starts = np.cumsum([0] + [len(d) for d in datasets])
    bound = (limits.max_length_change, limits.max_angle_change)

    def confirm(
        named: tuple[int, ...], risk: float, cap: int
    ) -> tuple[tuple[int, ...], float, np.ndarray, np.ndarray, np.ndarray] | None:
        drop = np.asarray(named, dtype=int)
        kept = []
        for i, d in enumerate(datasets):
            own = drop[(drop >= starts[i]) & (drop < starts[i + 1])] - starts[i]
            keep = np.setdiff1d(np.arange(len(d)), own)
            ids = None if d.ids is None else d.ids[keep]
            kept.append(dataclasses.replace(d, q_act=d.q_act[keep], values=d.values[keep], ids=ids))
        try:
            refit = identify_instruments(mech, params, kept, method=fit.result.method,
                                         labels=labels, weak_bound=bound)  # fmt: skip
            problem = InstrumentProblem(mech, params, datasets, labels)
            if problem.names != refit.names:
                return None
            r, J, _ = problem.evaluate(refit.values)
        except (PincalError, *TRIAL_FAILURES):
            return None
        m = int(starts[-1])
        if J is None or r.size != m:
            return None
        A = J[:, refit.fitted].reshape(m, 1, -1)
        z = np.asarray(r).reshape(m, 1)
        sigma = np.concatenate([np.ravel(s) for s in problem.sigma]).reshape(m, 1)
        return (*refit_outliers(A, z, named, risk, cap), A, z, sigma)

    return confirm
