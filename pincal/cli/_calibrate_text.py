"""The text and JSON that `pincal calibrate` prints and writes as report.txt."""

from __future__ import annotations

from pincal.identification import result_to_dict

__all__ = ["format_report", "result_json"]


def result_json(result, data_path: str, urdf: str | None = None) -> dict:
    """The identification result as ``identification.json`` (SI values and std).

    Built via :func:`pincal.identification.result_to_dict` with the data
    file (and the calibrated URDF) as annotations.
    """
    notes = {"data": data_path}
    if urdf is not None:
        notes["calibrated_urdf"] = urdf
    return result_to_dict(result, notes)


def format_report(doc: dict) -> str:
    """Human-readable identification report: values and 2σ in µm / µrad (as report.md).

    Position and orientation are reported apart, each over its measured components
    (named: ``position (x y)``, ``orientation (rz)``) and in its own unit.
    """
    from pincal.report import block_label

    comps = tuple(doc.get("components") or ()) or None
    measured = f", measured components {' '.join(comps)}" if comps else ""
    lines = [
        f"pincal calibration of {doc['model']} (preset {doc['preset']}, {doc['method']})",
        f"data: {doc['data']} ({doc['poses']} poses{measured})",
        f"solver: {doc['message']} after {doc['iterations']} iterations; "
        f"reduced chi2 {doc['reduced_chi2']:.4g}",
    ]
    ident = doc.get("identifiability")
    if ident:
        lines.append(f"identifiable: {ident['rank']} of {ident['parameters']} parameters")
        lines += [f"  {t}" for t in ident["explanation"]]
    lines.append("")
    w = doc.get("weighting") or {}
    if w.get("position_std") is not None or w.get("orientation_std") is not None:
        pos, ori = w.get("position_std"), w.get("orientation_std")
        s_after = doc["residuals"]["after"]
        if comps is not None:  # the σ of a block not measured is not shown
            pos = pos if s_after["rms_position_mm"] is not None else None
            ori = ori if s_after["rms_orientation_mrad"] is not None else None
        parts = [f"{block_label('position', comps)} {pos * 1e6:.3f} µm" if pos is not None else "",
                 f"{block_label('orientation', comps)} {ori * 1e6:.3f} µrad"
                 if ori is not None else ""]  # fmt: skip
        lines.append(f"noise (1σ, {w.get('source', '?')}): " + ", ".join(x for x in parts if x))
    header = f"{'parameter':32s} {'value':>14s} {'2σ':>12s}  (µm for lengths, µrad for angles)"
    lines += ["", header]
    for p in doc["parameters"]:
        two_sigma = 2 * p["std"] if p["std"] is not None else float("nan")
        if p["unit"] not in ("m", "rad"):  # a joint term: SI, its unit named
            lines.append(f"{p['name']:32s} {p['value']:+14.4g} {two_sigma:12.4g}  {p['unit']}")
            continue
        unit = "µm" if p["unit"] == "m" else "µrad"
        lines.append(f"{p['name']:32s} {p['value'] * 1e6:+14.3f} {two_sigma * 1e6:12.3f}  {unit}")
    lines.append("")
    for when in ("before", "after"):
        s = doc["residuals"][when]
        parts = []
        if s["rms_position_mm"] is not None:
            parts.append(
                f"{block_label('position', comps)} RMS {s['rms_position_mm']:.6f} max "
                f"{s['max_position_mm']:.6f} mm"
            )
        if s["rms_orientation_mrad"] is not None:
            parts.append(
                f"{block_label('orientation', comps)} RMS {s['rms_orientation_mrad']:.6f} max "
                f"{s['max_orientation_mrad']:.6f} mrad"
            )
        lines.append(f"residuals {when:6s}: " + "; ".join(parts))
    from pincal.cli._gate import quality_lines
    from pincal.cli._sockets import socket_lines

    lines += socket_lines(doc)
    gauge = doc.get("gauge") or ()
    if gauge:  # what an instrument fit does not observe (held at nominal)
        lines.append("not calibrated (held at nominal; the data do not observe it):")
        lines += [f"  {g}" for g in gauge]
    return "\n".join(lines + quality_lines(doc.get("quality"))) + "\n"
