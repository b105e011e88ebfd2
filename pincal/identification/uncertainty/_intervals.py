"""Confidence intervals and joint regions of a fit: normal / χ² or Student-t / F.

With the noise declared, the covariance is known up to the linearisation: a parameter's
95 % interval is ``±z·σ`` (z = 1.96) and the joint 95 % region of the k fitted
parameters is ``d² ≤ χ²_k(0.95)`` (d the Mahalanobis distance). With the noise scale
estimated from the residuals the covariance carries that estimate's sampling error:
the interval is ``±t_ν·σ`` and the region ``d² ≤ k·F_{k,ν}(0.95)`` with ν the residual
degrees of freedom. A fit with several noise blocks (position, orientation) estimates
one scale per block; ν is then the smallest block's redundancy (``n_b − tr(H_bb)``) —
conservative, as a joint region's coverage is set by its worst-determined scale — and
below :data:`APPROXIMATE_DOF` the quantiles are marked approximate.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

from pincal.identification._distributions import chi2_isf, f_isf, norm_ppf, t_ppf

__all__ = ["APPROXIMATE_DOF", "Intervals", "interval_quantiles"]

#: below this residual dof the Student-t / F quantiles of an estimated noise are approximate
APPROXIMATE_DOF = 30.0


@dataclass(frozen=True)
class Intervals:
    """The multipliers of σ and of k for a fit's intervals and joint region.

    Attributes:
        level: the confidence level (e.g. 0.95).
        k: the fitted parameters (the region's dimension).
        dof: the residual degrees of freedom of an estimated noise (None: declared).
        each: a parameter's interval is ±each·σ (z or t_ν quantile).
        joint: the joint region is d² ≤ joint (χ²_k or k·F_{k,ν} quantile).
    """

    level: float
    k: int
    dof: float | None
    each: float
    joint: float

    @property
    def estimated(self) -> bool:
        """The noise scale was estimated (Student-t / F quantiles)."""
        return self.dof is not None

    @property
    def approximate(self) -> bool:
        """Estimated on fewer than :data:`APPROXIMATE_DOF` residual degrees of freedom."""
        return self.dof is not None and self.dof < APPROXIMATE_DOF

    def to_dict(self) -> dict[str, object]:
        """JSON-ready (``quality.uncertainty.intervals``)."""
        return {"level": self.level, "k": self.k,
                "noise": "estimated" if self.estimated else "declared",
                "dof": self.dof, "quantile": "student-t / F" if self.estimated else "normal / χ²",
                "each_sigma": self.each, "joint_d2": self.joint,
                "approximate": self.approximate}  # fmt: skip

    def describe(self) -> str:
        """One sentence for the report (empty with declared noise)."""
        if not self.estimated:
            return ""
        pct = f"{100 * self.level:g} %"
        text = (f"the noise is estimated from the residuals on ν = {self.dof:.3g} degrees of "
                f"freedom: a {pct} interval is ±{self.each:.3g}σ (Student t), not ±2σ, and "
                f"the joint {pct} region of the {self.k} parameters is d² ≤ {self.joint:.4g} "
                f"(k·F), not χ²")  # fmt: skip
        if self.approximate:
            text += (f"; approximate below ν = {APPROXIMATE_DOF:g} (one scale per noise "
                     "block: more poses, or a declared noise, make them exact)")  # fmt: skip
        return text


def interval_quantiles(
    k: int,
    redundancy: Mapping[str, float] | None = None,
    *,
    estimated: bool = False,
    level: float = 0.95,
) -> Intervals:
    """The quantiles of a fit's intervals and joint region (module doc).

    Args:
        k: fitted parameters.
        redundancy: {block: n_b − tr(H_bb)} of the fit (its weighting's).
        estimated: the noise scale was estimated from the residuals.
        level: confidence level in (0, 1).
    """
    k = max(int(k), 1)
    dof = min(redundancy.values()) if estimated and redundancy else None
    if dof is None or not math.isfinite(dof) or dof <= 0:
        each = norm_ppf(0.5 + level / 2)
        return Intervals(level, k, None, each, chi2_isf(1.0 - level, k))
    each = t_ppf(0.5 + level / 2, dof)
    return Intervals(level, k, float(dof), each, k * f_isf(1.0 - level, k, dof))
