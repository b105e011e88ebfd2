"""The plain-text report of a calibration (``report.txt``, printed by `pincal calibrate`).

Rendered from an :class:`IdentificationRecord` — a live
:class:`pincal.identification.IdentificationResult`, or the record read back from
``identification.json`` by :func:`pincal.io.read_identification`, which give the same
text — and its context notes (the data file, the quality gate's record, an instrument
fit's gauge and sockets). Values and 2σ in µm / µrad, residuals in mm / mrad.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from pincal.identification import IdentificationRecord, QualityVerdict, held_summary
from pincal.report._sections import block_label
from pincal.report._uncertainty_text import uncertainty_lines

__all__ = ["calibration_text", "quality_lines"]


def _finite(v: float) -> bool:
    return math.isfinite(float(v))


def _header(
    result: IdentificationRecord, notes: Mapping[str, Any], comps: tuple[str, ...] | None
) -> list[str]:
    """Model, data, solver, identifiability and noise lines."""
    measured = f", measured components {' '.join(comps)}" if comps else ""
    lines = [
        f"pincal calibration of {result.model} (preset {result.preset}, {result.method})",
        f"data: {notes.get('data')} ({int(result.residuals.shape[0])} poses{measured})",
        f"solver: {result.message} after {int(result.iterations)} iterations; "
        f"reduced chi2 {float(result.reduced_chi2):.4g}",
    ]
    ident = result.identifiability_summary
    if ident is not None:
        held = held_summary(notes)
        lines.append(f"identifiable: {ident.rank} of {ident.parameters} parameters"
                     + (f" ({held})" if held else ""))  # fmt: skip
        lines += [f"  {t}" for t in ident.explanation]
    lines.append("")
    w = result.weighting
    if w is None:
        return lines
    pos = w.position_std if _finite(w.position_std) else None
    ori = w.orientation_std if _finite(w.orientation_std) else None
    if pos is None and ori is None:
        return lines
    if comps is not None:  # the σ of a block not measured is not shown
        pos = pos if not math.isnan(result.after.rms_position) else None
        ori = ori if not math.isnan(result.after.rms_orientation) else None
    parts = [f"{block_label('position', comps)} {pos * 1e6:.3f} µm" if pos is not None else "",
             f"{block_label('orientation', comps)} {ori * 1e6:.3f} µrad"
             if ori is not None else ""]  # fmt: skip
    lines.append(f"noise (1σ, {w.source}): " + ", ".join(x for x in parts if x))
    return lines


def _parameter_lines(result: IdentificationRecord) -> list[str]:
    """The identified parameters: value and 2σ in µm / µrad (a joint term in its SI unit)."""
    header = f"{'parameter':32s} {'value':>14s} {'2σ':>12s}  (µm for lengths, µrad for angles)"
    lines = ["", header]
    sel = np.flatnonzero(result.identified)
    for k, std in zip(sel, result.std, strict=True):
        name, unit, value = result.names[k], result.units[k], float(result.full_values[k])
        two_sigma = 2 * float(std)
        if unit not in ("m", "rad"):  # a joint term: SI, its unit named
            lines.append(f"{name:32s} {value:+14.4g} {two_sigma:12.4g}  {unit}")
            continue
        u = "µm" if unit == "m" else "µrad"
        lines.append(f"{name:32s} {value * 1e6:+14.3f} {two_sigma * 1e6:12.3f}  {u}")
    return lines


def _residual_lines(result: IdentificationRecord, comps: tuple[str, ...] | None) -> list[str]:
    """RMS and max residual before and after, per measured block [mm, mrad]."""
    lines = [""]
    for when, s in (("before", result.before), ("after", result.after)):
        parts = []
        if not math.isnan(s.rms_position):
            parts.append(
                f"{block_label('position', comps)} RMS {s.rms_position * 1e3:.6f} max "
                f"{s.max_position * 1e3:.6f} mm"
            )
        if not math.isnan(s.rms_orientation):
            parts.append(
                f"{block_label('orientation', comps)} RMS {s.rms_orientation * 1e3:.6f} max "
                f"{s.max_orientation * 1e3:.6f} mrad"
            )
        lines.append(f"residuals {when:6s}: " + "; ".join(parts))
    return lines


def _socket_lines(notes: Mapping[str, Any]) -> list[str]:
    """An instrument fit's warnings, socket centres [mm] and the distances between them."""
    centres = notes.get("socket_centres_mm") or {}
    lines = [f"pincal: WARNING: {w}" for w in notes.get("warnings") or ()]
    if not centres:
        return lines
    lines.append("socket centres [mm]: " + "; ".join(
        f"{k} ({', '.join(f'{v:.3f}' for v in c)})" for k, c in centres.items()))  # fmt: skip
    names = list(centres)[:8]
    pairs = [(a, b) for i, a in enumerate(names) for b in names[i + 1 :]]
    if pairs:
        lines.append("distances between them [mm]: " + "; ".join(
            f"{a}–{b} {np.linalg.norm(np.subtract(centres[a], centres[b])):.4f}"
            for a, b in pairs))  # fmt: skip
    return lines


def quality_lines(
    quality: QualityVerdict | Mapping[str, Any] | None, loss: str = "linear"
) -> list[str]:
    """Lines for the quality gate's verdict.

    Args:
        quality: the verdict, or its record (:meth:`QualityVerdict.to_dict`, with
            ``overridden`` and the uncertainty check's ``uncertainty``, as written in
            ``identification.json``'s ``quality``); None: no lines.
        loss: the fit's loss: a robust one already down-weights the outlier poses.
    """
    if isinstance(quality, QualityVerdict):
        quality = quality.to_dict()
    if not quality:
        return []
    if quality.get("passed"):
        lines = ["quality gate: passed"]
    elif quality.get("overridden"):
        lines = [f"quality gate: OVERRIDDEN with --force — {quality.get('reason')}"]
    else:
        lines = [f"quality gate: refused — {quality.get('reason')}"]
    lines += [f"  warning: {w['message']}" for w in quality.get("warnings", [])]
    blocks = [b for b in quality.get("chi2_blocks", []) if b.get("dof")]
    if blocks:
        lines.append("  χ² against the declared noise: " + "; ".join(
            f"{b['block']} χ²/ν {b['chi2'] / b['dof']:.3g} on {b['dof']:.0f} "
            f"(p = {b['p_value']:.2g})" for b in blocks))  # fmt: skip
    probes = [p for p in quality.get("probes", []) if not p["name"].startswith("trend:")]
    trends = [p for p in quality.get("probes", []) if p["name"].startswith("trend:")]
    if trends:  # one line for the pose-coordinate probes: the strongest trend only
        probes.append(min(trends, key=lambda p: p["p_value"]))
    if probes:
        lines.append("  misspecification probes: " + "; ".join(
            f"{p['size']} explains {p['explained']:.0%} (p = {p['p_value']:.2g})"
            for p in probes))  # fmt: skip
    blind = (quality.get("detection_floor") or {}).get("blind_spot")
    if blind:
        lines.append(f"  what the gate cannot see: {blind}")
    lines += uncertainty_lines(quality.get("uncertainty") or {})
    if quality.get("outlier_poses"):
        lines.append(
            f"  outlier poses (normalised residual > {quality.get('outlier_limit') or 0:.2f}): "
            f"{quality['outlier_poses']}; "
            + ("consider --loss huber" if loss == "linear"
               else f"down-weighted by the {loss} loss")
        )  # fmt: skip
    return lines


def calibration_text(result: IdentificationRecord, notes: Mapping[str, Any] | None = None) -> str:
    """The plain-text report of a calibration: values and 2σ in µm / µrad (as report.md).

    Position and orientation are reported apart, each over its measured components
    (named: ``position (x y)``, ``orientation (rz)``) and in its own unit.

    Args:
        result: the identification result, live or read from ``identification.json``.
        notes: context over ``result.annotations``: ``data`` (the data file(s)),
            ``quality`` (the gate's verdict or its record, see :func:`quality_lines`);
            a joint fit's ``gauge``, ``warnings`` and ``socket_centres_mm`` are read
            from ``result.joint``.

    Returns:
        The text, ending with a newline.
    """
    joint = {} if result.joint is None else result.joint.to_dict()
    ctx: dict[str, Any] = {**joint, **result.annotations, **(notes or {})}
    comps = tuple(result.components) or None
    lines = _header(result, ctx, comps)
    lines += _parameter_lines(result)
    lines += _residual_lines(result, comps)
    lines += _socket_lines(ctx)
    gauge = ctx.get("gauge") or ()
    if gauge:  # what an instrument fit does not observe (held at nominal)
        lines.append("not calibrated (held at nominal; the data do not observe it):")
        lines += [f"  {g}" for g in gauge]
    loss = result.weighting.loss if result.weighting is not None else "linear"
    return "\n".join(lines + quality_lines(ctx.get("quality"), loss)) + "\n"


