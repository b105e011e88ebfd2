"""Drift of a unit between two calibrations, judged with both calibrations' covariances.

A unit calibrated in two sessions gives estimates ``x₁`` (covariance ``C₁``) and ``x₂``
(``C₂``) of its parameters, from independent measurements. If the unit did not change,
``d = x₂ − x₁`` has covariance ``C₁ + C₂`` and

    T² = dᵀ (C₁ + C₂)⁺ d  ~  χ²(r)

over the parameters both sessions identified, ``r`` the rank of ``C₁ + C₂`` (directions
it does not resolve are left out, and said by ``dof``). A drift is declared when the
p-value is below ``alpha / K`` (Bonferroni over the K comparisons of the fleet): the
chance of one or more false drifts in the fleet is at most ``alpha`` — as far as the
covariances are the sessions' whole error. Model errors the calibration does not
represent (unmodelled geometry, temperature differences between sessions) move both
estimates alike only when the poses are the same; otherwise they show as drift.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pincal.workflow._fleet_stats import UnitEstimate

__all__ = ["DriftVerdict", "session_drift"]

#: eigenvalues of C₁ + C₂ below this fraction of the largest are directions left out
_RANK_TOL = 1e-10


@dataclass(frozen=True)
class DriftVerdict:
    """One unit's change between two consecutive sessions.

    Attributes:
        id: the unit's id.
        before: the earlier session's date; after: the later one's.
        distance: T², χ²(dof) without drift.
        dof: r, the rank of C₁ + C₂ over the parameters both sessions identified.
        p_value: P(χ²(dof) ≥ T²).
        drifted: p_value < alpha / K.
        largest: up to 3 ``(name, z, change)``: the parameters that moved most, ``z`` in
            σ of ``C₁ + C₂`` and ``change`` [m, rad] (both signed, after − before).
    """

    id: str
    before: str
    after: str
    distance: float
    dof: int
    p_value: float
    drifted: bool
    largest: tuple[tuple[str, float, float], ...]


def _compare(first: UnitEstimate, second: UnitEstimate) -> tuple[float, int, list]:
    names = [n for n in first.names if n in second.names]
    i1 = [first.names.index(n) for n in names]
    i2 = [second.names.index(n) for n in names]
    d = np.asarray(second.values, dtype=float)[i2] - np.asarray(first.values, dtype=float)[i1]
    S = np.asarray(first.covariance, dtype=float)[np.ix_(i1, i1)]
    S = S + np.asarray(second.covariance, dtype=float)[np.ix_(i2, i2)]
    w, V = np.linalg.eigh(S)
    keep = w > _RANK_TOL * max(float(w.max()), 1e-300)
    t = V[:, keep].T @ d
    distance = float(np.sum(t**2 / w[keep]))
    z = d / np.sqrt(np.maximum(np.diag(S), 1e-300))
    top = np.argsort(-np.abs(z))[:3]
    return distance, int(keep.sum()), [(names[j], float(z[j]), float(d[j])) for j in top]


def session_drift(
    sessions: Sequence[tuple[str, str, UnitEstimate]], alpha: float = 0.01
) -> tuple[DriftVerdict, ...]:
    """Drift between consecutive sessions of every unit calibrated more than once.

    Args:
        sessions: ``(id, date, estimate)`` of every calibrated session; units with one
            session are not compared. Dates are compared as text (ISO dates sort in time).
        alpha: fleet-wise false-alarm rate, in (0, 1).

    Returns:
        One :class:`DriftVerdict` per consecutive pair, by id then date.
    """
    from scipy import stats

    by_id: dict[str, list[tuple[str, UnitEstimate]]] = {}
    for uid, date, est in sessions:
        by_id.setdefault(uid, []).append((date, est))
    pairs = []
    for uid in sorted(by_id):
        runs = sorted(by_id[uid], key=lambda r: r[0])
        pairs += [(uid, a, b) for a, b in itertools.pairwise(runs)]
    limit = alpha / max(len(pairs), 1)
    out = []
    for uid, (d1, e1), (d2, e2) in pairs:
        distance, dof, largest = _compare(e1, e2)
        p = float(stats.chi2.sf(distance, dof)) if dof else 1.0
        out.append(DriftVerdict(uid, d1, d2, distance, dof, p, p < limit, tuple(largest)))
    return tuple(out)
