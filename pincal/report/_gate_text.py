"""What the quality gate measured besides its verdict, in sentences for the report.

From the ``quality`` record of a calibration (:meth:`QualityVerdict.to_dict`): the
held-out comparison that judged a fit with estimated noise (``held_out``) and the
misspecification probes (``probes``: name, share of the residual explained, F-test
p-value, size in words).
"""

from __future__ import annotations

from typing import Any

__all__ = ["gate_sentences"]


def gate_sentences(q: dict[str, Any], top: int = 4) -> list[str]:
    """The held-out comparison and the probes of a ``quality`` record, one sentence each.

    The probes are listed by the share they explain, the ``top`` largest; the sentences
    have no final full stop (the report adds it).
    """
    out = []
    held = q.get("held_out")
    if held:
        cal, base = held["calibrated"], held["baseline"]
        se = held.get("gain_standard_error_mm2")
        out.append(
            f"Held-out prediction ({held['folds']}-fold cross-validation, every fold refitted "
            f"from scratch) decides with the noise estimated: RMS "
            f"{cal['held_out_rms_mm']:.3f} mm calibrated against "
            f"{base['held_out_rms_mm']:.3f} mm for the {base['name']}; mean squared error "
            f"lower by {held['gain_mse_mm2']:.3g}"
            + (f" ± {se:.2g}" if se is not None else "")
            + " mm²"
        )
    probes = [p for p in q.get("probes") or [] if p.get("explained") is not None]
    probes.sort(key=lambda p: -p["explained"])
    if probes:
        role = "diagnostics, not refusals" if held else "each refuses past its threshold"
        listed = "; ".join(
            f"{p['size']} explains {p['explained']:.0%} (p = {p['p_value']:.2g})"
            for p in probes[:top]
        )
        more = len(probes) - top
        listed += f"; {more} more in calibration.json (quality.probes)" if more > 0 else ""
        out.append(f"Misspecification probes, the largest first ({role}): {listed}")
    return out
