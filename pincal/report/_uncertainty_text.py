"""How a calibration's σ were made, in words: the method, the intervals, a bootstrap beside.

Read from ``quality.uncertainty`` of calibration.json (see
:func:`pincal.identification.check_uncertainty`); printed by ``calibrate`` and written in
the report's quality section.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

__all__ = ["uncertainty_lines"]


def uncertainty_lines(unc: Mapping[str, Any]) -> list[str]:
    """How the σ above were made (``quality.uncertainty``), their intervals, a bootstrap.

    The σ are the linear ones, the linear ones plus a second-order term (instrument
    fits), or the linear ones inflated along the directions where the linearity check
    fails (method ``inflated``); a parametric bootstrap is reported beside, never as σ.
    """
    lines: list[str] = []
    method = unc.get("method")
    widest = unc.get("widened_max") or 1.0
    if method == "inflated":
        how = (
            "linear ones inflated along them by the measured spread"
            if unc.get("directions_inflated", 1)
            else "linear ones (along none does the cost rise less than predicted)"
        )
        lines.append(
            f"  uncertainties: not linear along {unc.get('directions_failed')} of the "
            f"{unc.get('directions_checked')} most uncertain directions; the σ above are the "
            f"{how}, plus the fit's second-order term (the combination it moves most: "
            f"{widest:.3g}× the linear σ)"
        )
    elif method == "second-order" and unc.get("curvature_excess") is not None:
        lines.append(
            f"  uncertainties: the fit's second-order error adds {unc['curvature_excess']:.2g} "
            f"to d²/k (limit {unc.get('curvature_limit')}); the σ above include it (the "
            f"combination it moves most: {widest:.3g}× the linear σ)"
        )
    elif unc.get("linear") and unc.get("directions_checked"):
        lines.append(
            f"  uncertainties: linear over one σ along the {unc.get('directions_checked')} "
            "most uncertain directions (the σ above are the linearised ones)"
        )
    iv = unc.get("intervals") or {}
    if iv.get("noise") == "estimated" and iv.get("dof") is not None:
        line = (f"  intervals: the noise is estimated on ν = {iv['dof']:.3g} residual degrees of "
                f"freedom: a {100 * iv['level']:g} % interval is ±{iv['each_sigma']:.3g}σ "
                f"(Student t), the joint region of the {iv['k']} parameters d² ≤ "
                f"{iv['joint_d2']:.4g} (k·F)")  # fmt: skip
        if iv.get("approximate"):
            line += "; approximate on so few degrees of freedom"
        lines.append(line)
    boot = unc.get("bootstrap")
    if boot:
        ratio = boot.get("largest_ratio")
        lines.append(
            f"  bootstrap: {boot['draws']} parametric refits (seed {boot.get('seed')}, "
            f"{boot.get('failed', 0)} failed) reported beside the σ, not as them"
            + (f"; its σ up to {ratio:.3g}× the linear ones" if ratio is not None else "")
        )
    return lines
