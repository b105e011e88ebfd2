"""Model selection by K-fold cross-validation: which error model do the data support?

Every candidate error model (e.g. registration only, geometric, geometric+compliance)
is fitted on K − 1 folds and predicts the held-out fold, on the same folds (from
:func:`pincal.validation.kfold`); a candidate's score is the held-out mean squared
position error over all poses. Standard errors are those of the paired per-pose
differences to the best candidate. The recommendation is the smallest candidate (fewest
identified parameters) whose held-out error is within one standard error of the best
(the one-standard-error rule): a term that does not lower the held-out error by more
than its scatter does not pay. Units: SI inside; :meth:`ModelSelection.lines` in mm.

Beside the held-out error, each candidate is fitted once on all poses for Akaike's and
Schwarz's information criteria, ``AIC = −2 ln L + 2k`` and ``BIC = −2 ln L + k ln n``
(k identified parameters, n scalar equations): ``−2 ln L`` is the χ² of the whitened
residuals when the noise is declared, and ``Σ_b n_b ln(RSS_b / n_b)`` over the position
and orientation blocks (Gaussian, σ per block unknown) when it is estimated. They are
asymptotic and assume the model family contains the truth; the recommendation stays the
cross-validated one. A robust fit (Huber…) or a fit without residual weighting has none.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from pincal.errors import MeasurementError
from pincal.identification import IdentificationResult
from pincal.measure import Measurements
from pincal.model import Mechanism, actual_joint_values, actual_shift
from pincal.validation._cross_validation import kfold, position_errors

__all__ = ["CandidateScore", "Fitted", "ModelSelection", "fitted", "select_model"]


@dataclass(frozen=True)
class Fitted:
    """One fit as a predictor.

    Attributes:
        errors: measurements → (m,) position errors [m] of the fit's prediction.
        n_parameters: parameters the fit identified.
    """

    errors: Callable[[Measurements], np.ndarray]
    n_parameters: int
    #: −2 ln L of the fit on its own data (see the module doc; None: not defined)
    neg2_loglik: float | None = None
    #: scalar equations of that fit (n of the BIC)
    n_equations: int = 0


def fitted(nominal: Mechanism, result: IdentificationResult) -> Fitted:
    """The predictor of an identification, its joint terms applied.

    Args:
        nominal: the mechanism the identification started from (the joint terms' basis
            is evaluated on it, as in the fit).
        result: the identification.
    """
    mech, params = result.calibrated_mechanism, result.parameter_set
    values = result.full_values

    def errors(meas: Measurements) -> np.ndarray:
        q = actual_joint_values(nominal, params, values, meas.q_act, meas.conditions)
        shift = actual_shift(nominal, params, values, meas.q_act, meas.conditions)
        return position_errors(
            mech, dataclasses.replace(meas, q_act=q, positions=meas.positions - shift)
        )

    return Fitted(errors, int(np.sum(result.identified)), _neg2_loglik(result),
                  int(result.n_equations))  # fmt: skip


def _neg2_loglik(result: IdentificationResult) -> float | None:
    """−2 ln L (constants dropped) of a least-squares fit, None when not defined."""
    w = result.weighting
    if w is None or w.loss != "linear" or w.whitened is None:
        return None
    if w.source in ("declared", "per-pose"):
        return float(np.sum(np.square(w.whitened)))
    comps = tuple(result.components)
    r = np.asarray(result.residuals, dtype=float)
    if len(comps) != r.shape[1]:
        return None
    total = 0.0
    for block in (("x", "y", "z"), ("rx", "ry", "rz")):
        cols = [j for j, c in enumerate(comps) if c in block]
        if cols:
            rss, n = float(np.sum(r[:, cols] ** 2)), r[:, cols].size
            total += n * np.log(max(rss, 1e-300) / n)
    return total


@dataclass(frozen=True)
class CandidateScore:
    """Held-out errors of one candidate.

    Attributes:
        name: the candidate's name.
        held_out: (m,) each pose's error [m] predicted by the fit that did not see it.
        n_parameters: identified parameters, mean over the folds.
        fit_rms: RMS position error [m] of the folds' fits on their own poses.
        aic, bic: information criteria of the fit on all poses (None: not defined).
    """

    name: str
    held_out: np.ndarray
    n_parameters: float
    fit_rms: float
    aic: float | None = None
    bic: float | None = None

    @property
    def mse(self) -> float:
        """Mean squared held-out error [m²]."""
        return float(np.mean(self.held_out**2))

    @property
    def rms(self) -> float:
        """RMS held-out error [m]."""
        return float(np.sqrt(self.mse))


@dataclass(frozen=True)
class ModelSelection:
    """The candidates ranked by K-fold held-out error.

    Attributes:
        k, seed: the folds' number and seed.
        scores: per candidate, in the order given.
        best: index of the lowest held-out mean squared error.
        excess: per candidate, (MSE − best MSE [m²], its standard error [m²]) from the
            paired per-pose differences.
        recommended: index of the smallest candidate within one standard error of the best.
    """

    k: int
    seed: int
    scores: tuple[CandidateScore, ...]
    best: int
    excess: tuple[tuple[float, float], ...]
    recommended: int

    def lines(self) -> list[str]:
        """A table [mm, mm²] and the recommendation, in words."""
        m = self.scores[0].held_out.size
        d_aic, d_bic = self.delta("aic"), self.delta("bic")
        out = [
            f"{self.k}-fold cross-validation, seed {self.seed} ({m} poses); held-out position "
            f"error, ΔMSE to the best ± its standard error (paired per pose); ΔAIC, ΔBIC of "
            f"the fit on all poses (to the lowest)",
            f"  {'model':38s} {'params':>6s} {'fit RMS':>8s} {'held-out RMS':>12s} "
            f"{'ΔMSE [mm²]':>18s} {'ΔAIC':>8s} {'ΔBIC':>8s}",
        ]
        for i, s in enumerate(self.scores):
            d, se = self.excess[i]
            mark = " best" if i == self.best else ""
            mark += " ← recommended" if i == self.recommended else ""
            ic = "".join(f" {'—':>8s}" if v is None else f" {v:8.4g}" for v in (d_aic[i], d_bic[i]))
            out.append(
                f"  {s.name:38s} {s.n_parameters:6.1f} {s.fit_rms * 1e3:6.3f}mm "
                f"{s.rms * 1e3:10.3f}mm {d * 1e6:+9.3g} ± {se * 1e6:<7.2g}{ic}{mark}"
            )
        rec, best = self.scores[self.recommended], self.scores[self.best]
        if self.recommended == self.best:
            out.append(f"recommended: {rec.name} (lowest held-out error)")
        else:
            out.append(
                f"recommended: {rec.name} — within one standard error of the best ({best.name}) "
                f"with fewer parameters: the extra terms of {best.name} do not pay on these data"
            )
        for key in ("aic", "bic"):
            vals = self.delta(key)
            if any(v is not None for v in vals):
                low = min((v, i) for i, v in enumerate(vals) if v is not None)[1]
                agree = "agrees with" if low == self.recommended else "differs from"
                out.append(f"lowest {key.upper()}: {self.scores[low].name} ({agree} the "
                           f"cross-validated recommendation)")  # fmt: skip
        return out

    def delta(self, key: str) -> list[float | None]:
        """Per candidate, its ``"aic"`` or ``"bic"`` minus the lowest (None: not defined)."""
        vals = [getattr(s, key) for s in self.scores]
        known = [v for v in vals if v is not None]
        if len(known) != len(vals):  # a candidate without one: not comparable
            return [None] * len(vals)
        return [v - min(known) for v in vals]

    def to_dict(self) -> dict:
        """For JSON [mm, mm²]."""
        return {
            "k": self.k,
            "seed": self.seed,
            "candidates": [
                {
                    "model": s.name,
                    "parameters": s.n_parameters,
                    "fit_rms_mm": s.fit_rms * 1e3,
                    "held_out_rms_mm": s.rms * 1e3,
                    "held_out_max_mm": float(s.held_out.max()) * 1e3,
                    "delta_mse_mm2": self.excess[i][0] * 1e6,
                    "delta_mse_standard_error_mm2": self.excess[i][1] * 1e6,
                    "aic": s.aic,
                    "bic": s.bic,
                    "delta_aic": self.delta("aic")[i],
                    "delta_bic": self.delta("bic")[i],
                }
                for i, s in enumerate(self.scores)
            ],
            "best": self.scores[self.best].name,
            "recommended": self.scores[self.recommended].name,
        }


def select_model(
    candidates: Mapping[str, Callable[[Measurements], Fitted]],
    meas: Measurements,
    k: int = 5,
    seed: int = 0,
) -> ModelSelection:
    """Rank candidate fitting procedures by K-fold held-out position error.

    Args:
        candidates: name → procedure (training measurements → :class:`Fitted`); each
            is refitted from scratch per fold (registration included), so nothing of
            a held-out pose reaches its prediction.
        meas: all poses (positions measured).
        k: folds (2 ≤ k ≤ m).
        seed: the folds' seed.

    Raises:
        MeasurementError: no candidate, bad K, no measured position.
    """
    if not candidates:
        raise MeasurementError("model selection needs at least one candidate model")
    folds = kfold(len(meas), k, seed)
    scores = []
    for name, fit in candidates.items():
        held = np.empty(len(meas))
        sizes, train_sq = [], []
        for rows in folds:
            train = np.setdiff1d(np.arange(len(meas)), rows)
            f = fit(meas.subset(train))
            held[rows] = f.errors(meas.subset(rows))
            train_sq.append(f.errors(meas.subset(train)) ** 2)
            sizes.append(f.n_parameters)
        fit_rms = float(np.sqrt(np.mean(np.concatenate(train_sq))))
        aic, bic = _criteria(fit(meas))
        scores.append(CandidateScore(name, held, float(np.mean(sizes)), fit_rms, aic, bic))
    mse = np.array([s.mse for s in scores])
    best = int(np.argmin(mse))
    excess = []
    for s in scores:
        d = s.held_out**2 - scores[best].held_out ** 2
        se = float(np.std(d, ddof=1) / np.sqrt(d.size)) if d.size > 1 else float("inf")
        excess.append((float(np.mean(d)), se))
    within = [i for i, (d, se) in enumerate(excess) if d <= se]
    recommended = min(within, key=lambda i: (scores[i].n_parameters, mse[i]))
    return ModelSelection(k, seed, tuple(scores), best, tuple(excess), recommended)


def _criteria(f: Fitted) -> tuple[float | None, float | None]:
    """(AIC, BIC) of a fit on all poses, (None, None) when its likelihood is not defined."""
    if f.neg2_loglik is None or f.n_equations <= 0:
        return None, None
    k = f.n_parameters
    return f.neg2_loglik + 2 * k, f.neg2_loglik + k * float(np.log(f.n_equations))
