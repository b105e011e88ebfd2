"""The report of a calibration output directory, read from its ``identification.json``.

The file is read by :func:`pincal.io.read_identification` (the one reader of the format)
as an :class:`pincal.identification.IdentificationRecord`; this module checks the
report's own annotations (validation errors, index history) and renders the record.
"""

from __future__ import annotations

import dataclasses
import math
import os
import tempfile
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any, SupportsFloat, cast

import numpy as np

from pincal.errors import CalibrationDirectoryError, ReportError
from pincal.identification import IdentificationRecord
from pincal.io import IDENTIFICATION_FILE, read_identification
from pincal.report._cross_validation import check_cross_validation, cross_validation_section
from pincal.report._document import ReportFiles, Section, Table, write_report
from pincal.report._plots import (
    plot_convergence,
    plot_index_history,
    plot_validation_summary,
)
from pincal.report._render import PlotJobs
from pincal.report._sections import (
    UNITS_NOTE,
    block_label,
    components_of,
    data_section,
    error_images,
    outlier_section,
    parameter_section,
    prediction_section,
    quality_section,
    residual_section,
)

__all__ = ["calibration_report"]

_ALL = ("x", "y", "z", "rx", "ry", "rz")
_SUMMARY_KEYS = (
    ("rms_position_mm", "RMS position [mm]"),
    ("max_position_mm", "max position [mm]"),
    ("rms_orientation_mrad", "RMS orientation [mrad]"),
    ("max_orientation_mrad", "max orientation [mrad]"),
)


def _number(value: object, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ReportError(f"{what} must be a number, got {value!r}")
    if not math.isfinite(float(value)):
        raise ReportError(f"{what} is NaN or infinite")
    return float(value)


def _numbers(value: object, what: str) -> np.ndarray:
    if not isinstance(value, list) or not value:
        raise ReportError(f"{what} must be a non-empty list of numbers")
    return np.array([_number(v, f"{what}[{k}]") for k, v in enumerate(value)])


def _check_annotations(notes: dict) -> None:
    """Validation summaries, per-pose validation errors and index history, if present."""
    for side in ("validation_before", "validation_after"):
        if side in notes:
            if not isinstance(notes[side], dict):
                raise ReportError(f"'{side}' must be an object")
            for key, _ in _SUMMARY_KEYS:
                if notes[side].get(key) is not None:
                    _number(notes[side][key], f"{side}.{key}")
    if "validation_errors" in notes:
        ve = notes["validation_errors"]
        if not isinstance(ve, dict) or not {"before", "after"} <= set(ve):
            raise ReportError("'validation_errors' must hold 'before' and 'after'")
        for side in ("before", "after"):
            if not isinstance(ve[side], dict):
                raise ReportError(f"validation_errors.{side} must be an object")
            for key in ("position", "orientation"):
                if key in ve[side]:
                    _numbers(ve[side][key], f"validation_errors.{side}.{key}")
    if "validation_components" in notes:
        vc = notes["validation_components"]
        if not isinstance(vc, list) or not vc or not set(vc) <= set(_ALL):
            raise ReportError(f"'validation_components' must list names from {' '.join(_ALL)}")
    if "cross_validation" in notes:
        check_cross_validation(notes["cross_validation"])
    if "index_history" in notes:
        ih = notes["index_history"]
        if not isinstance(ih, dict) or not ih:
            raise ReportError("'index_history' must be an object {index name: [values]}")
        for key, values in ih.items():
            _numbers(values, f"index_history.{key}")


def _read(path: Path) -> IdentificationRecord:
    """The result of ``path``, read by :func:`pincal.io.read_identification`.

    The report's annotations are checked: ``validation_before`` / ``validation_after``
    (``rms_position_mm, max_position_mm, rms_orientation_mrad, max_orientation_mrad``;
    null for a block not measured), ``validation_components``, ``validation_errors``
    (``{before|after: {position: [m], orientation: [rad]}}`` per validation pose),
    ``cross_validation`` (the ``cv`` object of ``pincal validate --cv``) and
    ``index_history`` (``{O1: [...], ...}``).

    Raises:
        ReportError: the file is missing or malformed, or an annotation is (named).
    """
    try:
        result = read_identification(path)
    except CalibrationDirectoryError as exc:
        raise ReportError(str(exc)) from None
    _check_annotations(dict(result.annotations))
    return result


_SUMMARY_LABELS = ("RMS position", "max position", "RMS orientation", "max orientation")
_SUMMARY_UNITS = ("µm", "µm", "µrad", "µrad")


def _r(value_mm: object) -> float:
    """A summary value [mm or mrad] in µm or µrad (NaN when absent)."""
    if value_mm is None:
        return float("nan")
    return round(float(cast(SupportsFloat, value_mm)) * 1e3, 3)


def _summary(result: IdentificationRecord) -> Section:
    facts = [f"Model {result.model}"]
    if result.preset:
        facts.append(f"parameter preset {result.preset!r}")
    facts.append(f"{int(result.identified.sum())} identified parameters")
    text = ", ".join(facts) + "."
    text += f"\n\nIdentification: {result.iterations} iterations"
    text += f", {result.message}" if result.message else ""
    if math.isfinite(result.reduced_chi2):
        text += f"; reduced χ² = {result.reduced_chi2:.4g} (≈ 1 when the noise model fits)"
    return Section("Summary", text + ".")


def _validation(notes: dict, plots: Path, jobs: PlotJobs) -> Section | None:
    before, after = notes.get("validation_before"), notes.get("validation_after")
    if before is None or after is None:
        return None
    comps = notes.get("validation_components")
    comps = tuple(comps) if comps else None
    rows = []
    for (key, _), label, unit in zip(_SUMMARY_KEYS, _SUMMARY_LABELS, _SUMMARY_UNITS, strict=True):
        if before.get(key) is None and after.get(key) is None:
            continue  # a block not measured
        stat, block = label.split(" ", 1)
        rows.append([f"{stat} {block_label(block, comps)}", unit,
                     _r(before.get(key)), _r(after.get(key))])  # fmt: skip
    images = [
        jobs.add(
            plot_validation_summary, before, after, path=plots / "validation_summary.png",
            labels={b: block_label(b, comps) for b in ("position", "orientation")},
        )
    ]  # fmt: skip
    ve: dict = notes.get("validation_errors") or {"before": {}, "after": {}}
    for key, unit in (("position", "um"), ("orientation", "urad")):
        measured = before.get(f"rms_{key}_{'mm' if unit == 'um' else 'mrad'}") is not None
        if measured and key in ve["before"] and key in ve["after"]:
            b, a = np.array(ve["before"][key]), np.array(ve["after"][key])
            images += error_images(
                jobs, b, a, unit, plots / f"validation_{key}",
                f"{block_label(key, comps).capitalize()} error", b.size == a.size,
                "validation pose",
            )  # fmt: skip
    over = f" over the components {' '.join(comps)}" if comps else ""
    source = notes.get("validation_source")
    text = (
        f"Errors of the predicted measured-frame pose on validation poses{over}, "
        "nominal vs calibrated model"
        + (f" ({source})" if isinstance(source, str) and source else "")
        + "."
    )
    tables = [Table(["quantity", "unit", "nominal model", "calibrated model"], rows)]
    predicted = notes.get("validation_predicted")
    if isinstance(predicted, dict):
        prows = []
        for kind, what in (("model", "calibrated model"), ("observed", "+ instrument noise")):
            for block, k, u in (("position", "mm", "µm"), ("orientation", "mrad", "µrad")):
                v = predicted.get(f"{kind}_rms_{block}_{k}")
                if v is not None:
                    prows.append([f"RMS {block_label(block, comps)}, {what}", u, _r(v)])
        if prows:
            kind = predicted.get("covariance") or "cramer-rao"
            head = ("Cramér–Rao prediction" if kind == "cramer-rao"
                    else f"prediction ({kind} covariance)")  # fmt: skip
            tables.append(Table([head, "unit", "value"], prows))
    return Section("Validation", text, images, tables)


def calibration_report(
    directory: str | os.PathLike,
    out: str | os.PathLike | None = None,
    *,
    name: str = "report",
    n_jobs: int | None = 1,
    notes: Mapping[str, Any] | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> ReportFiles:
    """Write the report of a calibration output directory: HTML, Markdown and JSON.

    Reads ``<directory>/identification.json`` (:func:`pincal.io.read_identification`) and
    writes ``<out>/<name>.html`` (self-contained: plots embedded), ``<name>.md`` and
    ``<name>.json`` with the same tables (lengths in µm, angles in µrad, 2σ
    uncertainties): data and noise (declared or estimated), residuals before/after,
    outliers (|r/σ| > 3) and robustly down-weighted poses, parameters with 2σ, poorly
    determined ones flagged, their correlations, Cramér–Rao prediction vs achievement,
    validation and convergence. ``out`` defaults to ``directory``; nothing else is
    read or changed.

    Args:
        directory: calibration output directory (holds ``identification.json``).
        out: folder of the written report; default ``directory``.
        name: file stem of the report files.
        n_jobs: processes drawing the plots (-1: every CPU; forked workers, see
            :mod:`pincal.report._render`); the files do not depend on it.
        notes: annotations added over the file's (e.g. :func:`campaign_notes` of a
            campaign's validation, truth and design files), checked like the file's.
        progress: optional callback ``(plots drawn, plots)`` after each plot.

    Raises:
        ReportError: the directory or its identification.json is missing or malformed,
            or ``n_jobs`` is not a positive integer or -1.
    """
    src = Path(directory)
    if not src.is_dir():
        raise ReportError(f"calibration directory {str(src)!r} does not exist")
    result = _read(src / IDENTIFICATION_FILE)
    if notes:
        _check_annotations(dict(notes))
        result = dataclasses.replace(result, annotations={**result.annotations, **notes})
    notes = dict(result.annotations)
    out_dir = Path(out) if out is not None else src
    files = sorted(p.name for p in src.iterdir() if p.suffix in (".urdf", ".yaml", ".json"))
    with tempfile.TemporaryDirectory(prefix="pincal-report-") as tmp:
        plots = Path(tmp)
        jobs = PlotJobs(scratch=True)  # drawn into ``tmp``, embedded, deleted
        data, noise = data_section(result, notes)
        sections = [_summary(result), data, residual_section(result, plots, jobs)]
        quality = quality_section(notes)
        if quality is not None:
            sections.insert(1, quality)
        outliers, out_idx, down_idx = outlier_section(result)
        sections.append(outliers)
        params, poor = parameter_section(result, plots, jobs)
        sections += [params, prediction_section(result)]
        validation = _validation(notes, plots, jobs)
        if validation is not None:
            sections.append(validation)
        if "cross_validation" in notes:
            sections.append(cross_validation_section(notes["cross_validation"]))
        extra_images = []
        if result.cost_history:
            extra_images.append(
                jobs.add(plot_convergence, list(result.cost_history),
                         path=plots / "convergence.png", ylabel="½‖r/σ‖²")
            )  # fmt: skip
        if "index_history" in notes:
            extra_images.append(
                jobs.add(
                    plot_index_history, notes["index_history"], path=plots / "index_history.png"
                )
            )
        if extra_images:
            w = result.weighting
            text = (
                f"Cost ½‖r/σ‖² per iteration; the noise was re-estimated between {w.rounds} "
                "fits, so the cost jumps where σ changed."
                if w is not None and w.source == "estimated" and w.rounds > 1
                else ""
            )
            sections.append(Section("Convergence and pose selection", text, extra_images))
        if files:
            sections.append(Section("Files", "Calibration output: " + ", ".join(files) + "."))
        summary = {
            "format": "pincal report",
            "version": 1,
            "units": UNITS_NOTE,
            "model": result.model,
            "preset": result.preset,
            "method": result.method,
            "noise": noise,
            "components": {
                "measured": list(components_of(result)),
                "position": [c for c in components_of(result) if c in _ALL[:3]],
                "orientation": [c for c in components_of(result) if c in _ALL[3:]],
            },
            "flags": {
                "poorly_determined": poor,
                "outlier_poses": out_idx,
                "downweighted_poses": down_idx,
            },
            "quality": notes.get("quality"),
        }
        jobs.render(n_jobs, progress)
        return write_report(
            out_dir,
            sections,
            title=f"Calibration report: {result.model}",
            name=name,
            markdown_images=False,
            json_data=summary,
        )
