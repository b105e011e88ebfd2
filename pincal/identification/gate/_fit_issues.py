"""Issues from the size of a fit: its χ², its σ̂, its parameter changes.

χ² against the declared noise, σ̂ against the instrument's profile, parameters moved
beyond their bound.

Used by :func:`pincal.identification.check_quality`; the thresholds are its
:class:`GateLimits` (see the :mod:`pincal.identification.gate._quality` module).
"""

from __future__ import annotations

import math

import numpy as np

from pincal.identification._distributions import chi2_sf
from pincal.identification._verdict import GateLimits, QualityIssue
from pincal.identification._weighting import Weighting
from pincal.identification.gate._instrument_profiles import InstrumentProfile
from pincal.identification.gate._misspecification import BlockChi2
from pincal.identification.results import IdentificationResult

__all__ = ["changes", "chi2_issues", "left_misfit", "profile_issues"]


#: an instrument fit's change beyond the bound refuses only beyond this many of its σ
SIGNIFICANT_CHANGE = 3.0


def changes(result: IdentificationResult, lim: GateLimits) -> list[QualityIssue]:
    """Parameters moved beyond their bound: machine parameters, registration unknowns.

    A change beyond the bound but within :data:`SIGNIFICANT_CHANGE` of the parameter's
    own σ is a warning — a direction the readings see weakly, wandering within its
    uncertainty (a 3-RRR ballbar's base coordinate 24 mm at σ 9 mm while the truth is
    within 1 mm; a RUSR crank 22 mm at σ 12 mm) — not a refusal; a runaway (a wrong
    joint reference: 300 mm at σ 0.45 mm) still refuses.
    """
    d = np.abs(np.asarray(result.full_values) - np.asarray(result.initial_values))
    sigma = np.full(d.size, np.inf)
    sigma[np.flatnonzero(result.identified)] = np.asarray(result.std, dtype=float)
    units = np.asarray(result.units)
    reg = np.array([n.rsplit(".", 1)[0] in lim.registration_joints for n in result.names],
                   dtype=bool)  # fmt: skip
    issues = []
    for kind, sel, length, angle, what in (
        ("change", ~reg, lim.max_length_change, lim.max_angle_change, "parameters"),
        ("registration", reg, lim.max_registration_length, lim.max_registration_angle,
         "registration parameters (instrument frame, marker)"),
    ):  # fmt: skip
        bound = np.where(units == "rad", angle, length)
        over = np.flatnonzero(sel & ((d > bound) | ~np.isfinite(d)))
        if over.size == 0:
            continue
        worst = int(over[np.argmax(d[over] / bound[over])])
        size = _amount(float(d[worst]), str(units[worst]))
        hint = "; change the bound with --max-change" if kind == "change" else ""
        runaway = ~(d[over] <= SIGNIFICANT_CHANGE * sigma[over])  # NaN σ: a runaway
        if not runaway.any():
            hint = (f", {d[worst] / sigma[worst]:.2g}σ: within {SIGNIFICANT_CHANGE:g}σ of "
                    "their own uncertainty, directions the readings see weakly; more poses "
                    "or a second instrument placement would pin them")  # fmt: skip
        issues.append(QualityIssue(
            kind, bool(runaway.any()),
            f"{over.size} {what} moved beyond {length * 1e3:g} mm / {angle:g} rad "
            f"(worst {result.names[worst]}: {size}{hint})",
        ))  # fmt: skip
    return issues


def _amount(value: float, unit: str) -> str:
    """A change in its own unit: mm for a length, rad, % for a gain (unit 1), else SI."""
    if unit == "m":
        return f"{value * 1e3:.4g} mm"
    if unit == "1":
        return f"{value * 100:.3g} %"
    return f"{value:.3g} {unit}"


def chi2_issues(
    chi2: float, blocks: list[BlockChi2], declared: bool, lim: GateLimits
) -> list[QualityIssue]:
    """χ² against the declared noise: per block p-value, and the hard χ²/ν limit."""
    if not declared:
        return []
    bad = [b for b in blocks
           if b.p_value < lim.chi2_significance and b.ratio > lim.min_chi2_ratio]  # fmt: skip
    if bad or not chi2 <= lim.max_reduced_chi2:
        parts = [
            f"{b.block} χ²/ν {b.ratio:.3g} on {b.dof:.0f} degrees of freedom (p = "
            f"{b.p_value:.2g} < {lim.chi2_significance:g}; residual RMS "
            f"{math.sqrt(b.ratio):.3g}× σ)"
            for b in bad
        ] or [f"reduced χ² {chi2:.3g} > {lim.max_reduced_chi2:g}"]
        return [QualityIssue(
            "chi2", True, "residuals larger than the declared noise: " + "; ".join(parts)
        )]  # fmt: skip
    low = [b for b in blocks if b.dof > 0 and b.ratio < 1e-2]
    if low:  # each block whose declared σ is ≥ 10× its residuals, with its factor
        return [QualityIssue(
            "low-chi2", False,
            f"{b.block} χ²/ν {b.ratio:.3g} < 0.01: the declared {b.block} noise is "
            f"{_factor(b.ratio)}× larger than its residuals; its σ and the parameters it "
            f"weighs are pessimistic (declare the instrument's {b.block} noise)",
        ) for b in low]  # fmt: skip
    if chi2 < 1e-2:
        return [QualityIssue(
            "low-chi2", False,
            f"reduced χ² {chi2:.3g} < 0.01: the declared noise is {_factor(chi2)}× larger "
            "than the residuals; the reported σ are pessimistic",
        )]  # fmt: skip
    return []


def _factor(ratio: float) -> str:
    """How many times the declared σ exceeds the residuals' for a χ²/ν ``ratio``."""
    return f"{1 / math.sqrt(ratio):.3g}" if ratio > 0 else "∞"


def profile_issues(w: Weighting, profile: InstrumentProfile, lim: GateLimits) -> list[QualityIssue]:
    """Estimated σ against the instrument profile's typical σ."""
    issues = []
    for block, est, typ, unit, f in (
        ("position", w.position_std, profile.position, "mm", 1e3),
        ("orientation", w.orientation_std, profile.orientation, "mrad", 1e3),
    ):
        if math.isfinite(est) and math.isfinite(typ) and est > lim.noise_factor * typ:
            issues.append(QualityIssue(
                "noise", True,
                f"the estimated {block} noise {est * f:.3g} {unit} is {est / typ:.3g}× the "
                f"typical {typ * f:.3g} {unit} of the {profile.name!r} profile "
                f"({profile.description}; limit {lim.noise_factor:g}×): model or instrument "
                "error suspected",
            ))  # fmt: skip
    return issues


def left_misfit(A: np.ndarray, z: np.ndarray, named: tuple[int, ...], lim: GateLimits) -> str:
    """What a refit without the named poses leaves unexplained, in words ('' if nothing).

    With declared noise, a few bad poses explain a misfit only when the fit without them
    passes the χ² test: ``χ² = Σ z²`` over the other poses against χ²(ν), ν their
    redundancy, refused as :func:`chi2_issues` refuses (p below ``chi2_significance``
    and χ²/ν above ``min_chi2_ratio``). A scaled bar or a wrong model leaves every
    reading off; the poses that stand out most are then no outliers.

    Args:
        A: (m, k, p) whitened Jacobian at the refit without the named poses.
        z: (m, k) whitened residuals there (declared σ).
        named: the pose indices named outliers.
        lim: the gate's thresholds.
    """
    from pincal.identification.gate._outliers import column_basis

    keep = np.setdiff1d(np.arange(z.shape[0]), np.asarray(named, dtype=int))
    nu = keep.size * z.shape[1] - column_basis(A[keep].reshape(-1, A.shape[2])).shape[1]
    if nu < 1:
        return ""
    chi2 = float(np.sum(z[keep] ** 2))
    p = chi2_sf(chi2, nu)
    if p < lim.chi2_significance and chi2 / nu > lim.min_chi2_ratio:
        return (f"without them the residuals are still χ²/ν {chi2 / nu:.3g} on {nu} (p = "
                f"{p:.2g}): the misfit is not a few bad poses")  # fmt: skip
    return ""
