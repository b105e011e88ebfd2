"""Plots and a Markdown + HTML report of a calibration.

All plots use matplotlib's Agg canvas directly (no pyplot, no window, no global
state) and are written atomically (temporary file + rename). Values are passed
in SI units (m, rad); a ``unit`` argument chooses the displayed unit:
``m, mm, um (µm), rad, mrad, urad (µrad), deg``.
"""

from __future__ import annotations

import html
import io
import json
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from pincal.errors import ReportError
from pincal.io._atomic import atomic_write_bytes

__all__ = [
    "ErrorStats",
    "ReportFiles",
    "Section",
    "Table",
    "calibration_report",
    "error_statistics",
    "plot_convergence",
    "plot_error_histogram",
    "plot_errors_before_after",
    "plot_index_history",
    "plot_parameters",
    "plot_validation_summary",
    "read_identification",
    "write_report",
]

#: display unit → (factor from SI, label)
_UNITS: dict[str, tuple[float, str]] = {
    "m": (1.0, "m"),
    "mm": (1e3, "mm"),
    "um": (1e6, "µm"),
    "µm": (1e6, "µm"),
    "rad": (1.0, "rad"),
    "mrad": (1e3, "mrad"),
    "urad": (1e6, "µrad"),
    "µrad": (1e6, "µrad"),
    "deg": (180.0 / math.pi, "deg"),
}
_BEFORE, _AFTER, _TRUE = "#d62728", "#1f77b4", "#2ca02c"


@dataclass(frozen=True)
class ErrorStats:
    """Summary of error magnitudes (same unit as the input).

    Attributes:
        rms: root mean square.
        max: largest absolute value.
        mean: mean absolute value.
        count: number of values.
    """

    rms: float
    max: float
    mean: float
    count: int


@dataclass(frozen=True)
class Table:
    """A table for a report: ``rows`` are sequences of cells (str or numbers)."""

    headers: Sequence[str]
    rows: Sequence[Sequence[object]]
    caption: str = ""


@dataclass(frozen=True)
class Section:
    """One report section: a heading, paragraphs of text, images and tables."""

    title: str
    text: str = ""
    images: Sequence[str | os.PathLike] = field(default_factory=tuple)
    tables: Sequence[Table] = field(default_factory=tuple)


@dataclass(frozen=True)
class ReportFiles:
    """Paths of a written report."""

    markdown: Path
    html: Path


# --------------------------------------------------------------------------- helpers


def _unit(unit: str) -> tuple[float, str]:
    try:
        return _UNITS[unit]
    except KeyError:
        raise ReportError(f"unit {unit!r} not known; units are: {', '.join(_UNITS)}") from None


def _vector(values: Sequence[float] | np.ndarray, what: str) -> np.ndarray:
    arr = np.asarray(values, dtype=float)
    if arr.ndim != 1 or arr.size == 0:
        raise ReportError(f"{what} must be a non-empty 1-D array (m,), got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ReportError(f"{what} contains NaN or inf")
    return arr


def _save(fig: Figure, path: str | os.PathLike) -> Path:
    buffer = io.BytesIO()
    FigureCanvasAgg(fig)
    fig.savefig(buffer, format="png", dpi=110)
    return atomic_write_bytes(path, buffer.getvalue())


def _figure(width: float = 7.0, height: float = 4.0) -> Figure:
    return Figure(figsize=(width, height), layout="constrained")


def error_statistics(values: Sequence[float] | np.ndarray) -> ErrorStats:
    """RMS, max and mean of ``|values|`` (shape (m,))."""
    arr = np.abs(_vector(values, "values"))
    return ErrorStats(
        rms=float(np.sqrt(np.mean(arr**2))),
        max=float(arr.max()),
        mean=float(arr.mean()),
        count=int(arr.size),
    )


# --------------------------------------------------------------------------- plots


def plot_errors_before_after(
    before: Sequence[float] | np.ndarray,
    after: Sequence[float] | np.ndarray,
    unit: str,
    path: str | os.PathLike,
    *,
    title: str = "Error per pose",
) -> Path:
    """Bar chart of the error at each pose before and after calibration.

    Args:
        before: error magnitudes, shape (m,) [m or rad].
        after: error magnitudes, shape (m,) [m or rad] (the same poses).
        unit: display unit (see module docstring).
        path: PNG file to write.
    """
    b = _vector(before, "before")
    a = _vector(after, "after")
    if a.shape != b.shape:
        raise ReportError(f"before has {b.size} poses but after has {a.size}")
    factor, label = _unit(unit)
    sb, sa = error_statistics(b * factor), error_statistics(a * factor)
    fig = _figure()
    ax = fig.add_subplot()
    x = np.arange(b.size)
    ax.bar(
        x - 0.2,
        np.abs(b) * factor,
        0.4,
        color=_BEFORE,
        label=f"before: RMS {sb.rms:.4g}, max {sb.max:.4g} {label}",
    )
    ax.bar(
        x + 0.2,
        np.abs(a) * factor,
        0.4,
        color=_AFTER,
        label=f"after: RMS {sa.rms:.4g}, max {sa.max:.4g} {label}",
    )
    ax.set_xlabel("pose")
    ax.set_ylabel(f"error [{label}]")
    ax.set_title(title)
    positive = np.abs(np.concatenate([a, b]))
    positive = positive[positive > 0]
    if positive.size and positive.max() > 20 * positive.min():
        ax.set_yscale("log")  # calibration typically shrinks errors by decades
    if b.size <= 30:
        ax.set_xticks(x)
    ax.legend()
    ax.grid(axis="y", alpha=0.3)
    return _save(fig, path)


def plot_error_histogram(
    before: Sequence[float] | np.ndarray,
    after: Sequence[float] | np.ndarray,
    unit: str,
    path: str | os.PathLike,
    *,
    title: str = "Error distribution",
    bins: int = 20,
) -> Path:
    """Overlaid histograms of error magnitudes before and after, shape (m,) each [m or rad]."""
    b = np.abs(_vector(before, "before"))
    a = np.abs(_vector(after, "after"))
    factor, label = _unit(unit)
    edges = np.linspace(0.0, max(b.max(), a.max()) * factor * 1.0001 or 1.0, bins + 1)
    fig = _figure()
    ax = fig.add_subplot()
    ax.hist(b * factor, edges, color=_BEFORE, alpha=0.6, label=f"before (n = {b.size})")
    ax.hist(a * factor, edges, color=_AFTER, alpha=0.6, label=f"after (n = {a.size})")
    ax.set_xlabel(f"error [{label}]")
    ax.set_ylabel("count")
    ax.set_title(title)
    ax.legend()
    return _save(fig, path)


def plot_index_history(
    history: Mapping[str, Sequence[float]] | Sequence[float] | np.ndarray,
    path: str | os.PathLike,
    *,
    title: str = "Observability index during pose selection",
) -> Path:
    """Observability indices per exchange iteration, one panel per index.

    Args:
        history: ``{"O1": [...], "O2": [...], ...}`` (each shape (iterations,)) or
            one sequence.
        path: PNG file to write.
    """
    series = dict(history) if isinstance(history, Mapping) else {"index": history}
    if not series:
        raise ReportError("history is empty; expected {name: values per iteration}")
    arrays = {name: _vector(v, f"history[{name!r}]") for name, v in series.items()}
    fig = _figure(7.0, 1.2 + 1.6 * len(arrays))
    axes = fig.subplots(len(arrays), 1, sharex=True, squeeze=False)[:, 0]
    for ax, (name, values) in zip(axes, arrays.items(), strict=True):
        ax.plot(np.arange(values.size), values, "o-", ms=3)
        ax.set_ylabel(name)
        ax.grid(alpha=0.3)
        positive = values > 0
        if positive.all() and values.max() / values.min() > 100:
            ax.set_yscale("log")
    axes[-1].set_xlabel("iteration")
    axes[0].set_title(title)
    return _save(fig, path)


def plot_convergence(
    cost_per_iter: Sequence[float] | np.ndarray,
    path: str | os.PathLike,
    *,
    title: str = "Convergence",
    ylabel: str = "cost",
) -> Path:
    """Cost (e.g. ½‖r‖² or residual RMS) per iteration, shape (iterations,), log scale."""
    cost = _vector(cost_per_iter, "cost_per_iter")
    fig = _figure()
    ax = fig.add_subplot()
    ax.plot(np.arange(cost.size), cost, "o-", ms=4)
    if np.all(cost > 0):
        ax.set_yscale("log")
    ax.set_xlabel("iteration")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(alpha=0.3, which="both")
    return _save(fig, path)


def _parameter_kind(name: str) -> str:
    dof = name.rsplit(".", 1)[-1]
    if dof in ("rx", "ry", "rz") or dof.startswith(("alpha", "theta")):
        return "angle"
    return "length"


def plot_parameters(
    names: Sequence[str],
    values: Sequence[float] | np.ndarray,
    std: Sequence[float] | np.ndarray,
    true: Sequence[float] | np.ndarray | None = None,
    path: str | os.PathLike | None = None,
    *,
    kinds: Sequence[str] | None = None,
    length_unit: str = "mm",
    angle_unit: str = "mrad",
    title: str = "Identified parameters (±2σ)",
) -> Path:
    """Identified parameter values with ±2σ bars, lengths and angles in separate panels.

    Args:
        names: parameter names, shape (L,) (``<joint>.<dof>``).
        values: identified values, shape (L,) [m or rad].
        std: standard deviations, shape (L,) [m or rad].
        true: true values (simulation), shape (L,), drawn as markers, or None.
        path: PNG file to write (required).
        kinds: ``"length"`` or ``"angle"`` per parameter; by default inferred from
            the dof (``rx, ry, rz`` → angle, otherwise length).
        length_unit, angle_unit: display units of the two panels.
    """
    if path is None:
        raise ReportError("path is required")
    names = [str(n) for n in names]
    v = _vector(values, "values")
    s = _vector(std, "std")
    t = None if true is None else _vector(true, "true")
    for what, arr in (("values", v), ("std", s), ("true", t)):
        if arr is not None and arr.size != len(names):
            raise ReportError(f"{what} has {arr.size} entries but there are {len(names)} names")
    if np.any(s < 0):
        raise ReportError("std must be non-negative")
    kinds = list(kinds) if kinds is not None else [_parameter_kind(n) for n in names]
    if len(kinds) != len(names) or not set(kinds) <= {"length", "angle"}:
        raise ReportError("kinds must hold 'length' or 'angle' for each name")
    groups = [
        (kind, unit, [i for i, k in enumerate(kinds) if k == kind])
        for kind, unit in (("length", length_unit), ("angle", angle_unit))
    ]
    groups = [g for g in groups if g[2]]
    height = 1.5 + 0.22 * len(names) + 0.6 * len(groups)
    fig = _figure(7.5, max(3.0, height))
    axes = fig.subplots(
        len(groups), 1, squeeze=False, height_ratios=[len(g[2]) + 2 for g in groups]
    )[:, 0]
    for ax, (kind, unit, idx) in zip(axes, groups, strict=True):
        factor, label = _unit(unit)
        y = np.arange(len(idx))[::-1]
        ax.errorbar(
            v[idx] * factor,
            y,
            xerr=2 * s[idx] * factor,
            fmt="o",
            color=_AFTER,
            ecolor=_AFTER,
            capsize=3,
            ms=4,
            label="identified ±2σ",
        )
        if t is not None:
            ax.plot(t[idx] * factor, y, "x", color=_TRUE, ms=7, mew=2, label="true")
        ax.axvline(0.0, color="0.6", lw=0.8)
        ax.set_yticks(y)
        ax.set_yticklabels([names[i] for i in idx], fontsize=8)
        ax.set_xlabel(f"{kind} [{label}]")
        ax.grid(axis="x", alpha=0.3)
        ax.legend(fontsize=8, loc="best")
    axes[0].set_title(title)
    return _save(fig, path)


# --------------------------------------------------------------------------- report


def _cell(value: object) -> str:
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)


def _markdown_table(table: Table) -> str:
    lines = []
    if table.caption:
        lines.append(f"*{table.caption}*\n")
    lines.append("| " + " | ".join(str(h) for h in table.headers) + " |")
    lines.append("|" + "|".join(" --- " for _ in table.headers) + "|")
    for row in table.rows:
        cells = [_cell(c).replace("|", "\\|") for c in row]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _html_table(table: Table) -> str:
    parts = ["<table>"]
    if table.caption:
        parts.append(f"<caption>{html.escape(table.caption)}</caption>")
    parts.append("<tr>" + "".join(f"<th>{html.escape(str(h))}</th>" for h in table.headers))
    for row in table.rows:
        parts.append("<tr>" + "".join(f"<td>{html.escape(_cell(c))}</td>" for c in row))
    parts.append("</table>")
    return "\n".join(parts)


_HTML_PAGE = """<!DOCTYPE html>
<html>
<head>
<meta charset="utf-8">
<title>{title}</title>
<style>
body {{ font: 15px/1.5 sans-serif; max-width: 60em; margin: 2em auto; padding: 0 1em;
  color: #222; }}
img {{ max-width: 100%; border: 1px solid #ddd; margin: 0.5em 0; }}
table {{ border-collapse: collapse; margin: 0.8em 0; }}
th, td {{ border: 1px solid #bbb; padding: 2px 8px; text-align: right; }}
th {{ background: #eee; }}
caption {{ caption-side: top; font-style: italic; text-align: left; }}
</style>
</head>
<body>
<h1>{title}</h1>
{body}
</body>
</html>
"""


def write_report(
    directory: str | os.PathLike,
    sections: Sequence[Section],
    *,
    title: str = "pincal calibration report",
    name: str = "report",
) -> ReportFiles:
    """Write ``<name>.md`` and ``<name>.html`` into ``directory``.

    Images are referenced by their path relative to ``directory`` (put the PNGs
    there or below so the report can be moved as one folder); missing images are
    an error. Both files are written atomically.
    """
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    md = [f"# {title}", ""]
    body = []
    for section in sections:
        md += [f"## {section.title}", ""]
        body.append(f"<h2>{html.escape(section.title)}</h2>")
        if section.text:
            md += [section.text, ""]
            for paragraph in section.text.split("\n\n"):
                body.append(f"<p>{html.escape(paragraph)}</p>")
        for image in section.images:
            image_path = Path(image)
            if not image_path.is_absolute():
                image_path = out / image_path
            if not image_path.is_file():
                raise ReportError(f"image {str(image)!r} of section {section.title!r} not found")
            rel = Path(os.path.relpath(image_path.resolve(), out.resolve())).as_posix()
            md += [f"![{image_path.stem}]({rel})", ""]
            body.append(f'<img src="{html.escape(rel)}" alt="{html.escape(image_path.stem)}">')
        for table in section.tables:
            md += [_markdown_table(table), ""]
            body.append(_html_table(table))
    md_path = atomic_write_bytes(out / f"{name}.md", "\n".join(md).encode("utf-8"))
    html_text = _HTML_PAGE.format(title=html.escape(title), body="\n".join(body))
    html_path = atomic_write_bytes(out / f"{name}.html", html_text.encode("utf-8"))
    return ReportFiles(markdown=md_path, html=html_path)


# --------------------------------------------------------------------------- calibration report

#: name of the calibration summary written by a calibration run
IDENTIFICATION_JSON = "identification.json"
#: largest identification.json read [bytes]
MAX_JSON_BYTES = 20_000_000
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


def read_identification(path: str | os.PathLike) -> dict:
    """Read and check a calibration summary (``identification.json``).

    Required: ``model`` (str) and ``parameters`` (list of ``{name, value, std, unit}``,
    SI units). Optional, each drawn when present: ``preset``, ``validation_before`` /
    ``validation_after`` (``rms_position_mm, max_position_mm, rms_orientation_mrad,
    max_orientation_mrad``), ``reduced_chi2``, ``iterations``, ``message``,
    ``cost_history`` (list per iteration), ``parameters[i].true`` (simulation truth
    [SI]), ``validation_errors`` (``{before|after: {position: [m], orientation:
    [rad]}}`` per validation pose) and ``index_history`` (``{O1: [...], ...}``).

    Raises:
        ReportError: missing file, invalid JSON or a malformed entry (the message
            names the entry).
    """
    path = Path(path)
    try:
        raw = path.read_bytes()[: MAX_JSON_BYTES + 1]
    except OSError as exc:
        raise ReportError(f"cannot read {str(path)!r}: {exc.strerror}") from exc
    if len(raw) > MAX_JSON_BYTES:
        raise ReportError(f"{str(path)!r} is larger than {MAX_JSON_BYTES} bytes")
    try:
        data = json.loads(raw.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ReportError(f"{str(path)!r} is not valid JSON: {exc}") from exc
    if not isinstance(data, dict):
        raise ReportError(f"{str(path)!r} must hold a JSON object, got {type(data).__name__}")
    if not isinstance(data.get("model"), str):
        raise ReportError(f"{str(path)!r}: 'model' (the model name) is missing")
    params = data.get("parameters")
    if not isinstance(params, list) or not params:
        raise ReportError(f"{str(path)!r}: 'parameters' must be a non-empty list")
    for k, p in enumerate(params):
        if not isinstance(p, dict) or not isinstance(p.get("name"), str):
            raise ReportError(f"parameters[{k}] must be an object with a 'name'")
        for key in ("value", "std"):
            _number(p.get(key), f"parameters[{k}].{key}")
        if "true" in p:
            _number(p["true"], f"parameters[{k}].true")
        if p.get("unit", "m") not in ("m", "rad"):
            raise ReportError(f"parameters[{k}].unit must be 'm' or 'rad', got {p.get('unit')!r}")
    for side in ("validation_before", "validation_after"):
        if side in data:
            if not isinstance(data[side], dict):
                raise ReportError(f"'{side}' must be an object")
            for key, _ in _SUMMARY_KEYS:
                if key in data[side]:
                    _number(data[side][key], f"{side}.{key}")
    if "cost_history" in data:
        _numbers(data["cost_history"], "cost_history")
    if "validation_errors" in data:
        ve = data["validation_errors"]
        if not isinstance(ve, dict) or not {"before", "after"} <= set(ve):
            raise ReportError("'validation_errors' must hold 'before' and 'after'")
        for side in ("before", "after"):
            if not isinstance(ve[side], dict):
                raise ReportError(f"validation_errors.{side} must be an object")
            for key in ("position", "orientation"):
                if key in ve[side]:
                    _numbers(ve[side][key], f"validation_errors.{side}.{key}")
    if "index_history" in data:
        ih = data["index_history"]
        if not isinstance(ih, dict) or not ih:
            raise ReportError("'index_history' must be an object {index name: [values]}")
        for key, values in ih.items():
            _numbers(values, f"index_history.{key}")
    return data


def plot_validation_summary(
    before: Mapping[str, float], after: Mapping[str, float], path: str | os.PathLike
) -> Path:
    """Grouped bars of RMS and max position [mm] / orientation [mrad] errors, before vs after."""
    fig = _figure(7.5, 3.6)
    axes = fig.subplots(1, 2)
    for ax, (quantity, unit) in zip(
        axes, (("position", "mm"), ("orientation", "mrad")), strict=True
    ):
        keys = [f"rms_{quantity}_{unit}", f"max_{quantity}_{unit}"]
        b = [float(before.get(k, np.nan)) for k in keys]
        a = [float(after.get(k, np.nan)) for k in keys]
        x = np.arange(2)
        bars_b = ax.bar(x - 0.2, b, 0.4, color=_BEFORE, label="nominal model")
        bars_a = ax.bar(x + 0.2, a, 0.4, color=_AFTER, label="calibrated model")
        ax.bar_label(bars_b, fmt="%.3g", fontsize=8)
        ax.bar_label(bars_a, fmt="%.3g", fontsize=8)
        ax.set_xticks(x)
        ax.set_xticklabels(["RMS", "max"])
        ax.set_ylabel(f"{quantity} error [{unit}]")
        positive = [v for v in b + a if v > 0]
        if positive and max(positive) / min(positive) > 30:
            ax.set_yscale("log")
        ax.grid(axis="y", alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle("Validation: predicted vs actual measured-frame pose")
    return _save(fig, path)


def _display(value: float, unit: str) -> tuple[float, str]:
    return (value * 1e6, "µm") if unit == "m" else (value * 1e6, "µrad")


def calibration_report(
    directory: str | os.PathLike,
    out: str | os.PathLike | None = None,
    *,
    name: str = "report",
) -> ReportFiles:
    """Assemble plots and numbers of a calibration output directory into one report.

    Reads ``<directory>/identification.json`` (see :func:`read_identification`)
    and writes ``<out>/<name>.md``, ``<out>/<name>.html`` and their PNG plots in
    ``<out>/<name>_plots/`` (``out`` defaults to ``directory``). Nothing else is
    read or changed.

    Raises:
        ReportError: the directory or its identification.json is missing or malformed.
    """
    src = Path(directory)
    if not src.is_dir():
        raise ReportError(f"calibration directory {str(src)!r} does not exist")
    data = read_identification(src / IDENTIFICATION_JSON)
    out_dir = Path(out) if out is not None else src
    plots = (out_dir / f"{name}_plots").resolve()
    sections: list[Section] = []

    facts = [f"Model {data['model']}"]
    if "preset" in data:
        facts.append(f"parameter preset {data['preset']!r}")
    facts.append(f"{len(data['parameters'])} identified parameters")
    text = ", ".join(facts) + "."
    if "iterations" in data or "message" in data:
        text += f"\n\nIdentification: {data.get('iterations', '?')} iterations"
        text += f", {data['message']}" if data.get("message") else ""
        if isinstance(data.get("reduced_chi2"), (int, float)):
            text += (
                f"; reduced χ² = {float(data['reduced_chi2']):.4g} (≈ 1 when the noise model fits)"
            )
        text += "."
    sections.append(Section("Summary", text))

    before, after = data.get("validation_before"), data.get("validation_after")
    if before is not None and after is not None:
        rows = [
            [label, float(before.get(key, np.nan)), float(after.get(key, np.nan))]
            for key, label in _SUMMARY_KEYS
        ]
        images = [plot_validation_summary(before, after, plots / "validation_summary.png")]
        ve = data.get("validation_errors")
        if ve:
            for key, unit in (("position", "mm"), ("orientation", "mrad")):
                if key in ve["before"] and key in ve["after"]:
                    b, a = np.array(ve["before"][key]), np.array(ve["after"][key])
                    if b.size == a.size:
                        images.append(
                            plot_errors_before_after(
                                b,
                                a,
                                unit,
                                plots / f"validation_{key}.png",
                                title=f"{key.capitalize()} error per validation pose",
                            )
                        )
                    images.append(
                        plot_error_histogram(
                            b,
                            a,
                            unit,
                            plots / f"validation_{key}_histogram.png",
                            title=f"{key.capitalize()} error distribution",
                        )
                    )
        sections.append(
            Section(
                "Validation",
                "Errors of the predicted measured-frame pose on validation poses, "
                "nominal vs calibrated model.",
                images,
                [Table(["quantity", "nominal", "calibrated"], rows)],
            )
        )

    params = data["parameters"]
    names = [p["name"] for p in params]
    values = np.array([float(p["value"]) for p in params])
    std = np.array([float(p["std"]) for p in params])
    kinds = ["angle" if p.get("unit", "m") == "rad" else "length" for p in params]
    true = (
        np.array([float(p["true"]) for p in params]) if all("true" in p for p in params) else None
    )
    image = plot_parameters(
        names,
        values,
        std,
        true,
        plots / "parameters.png",
        kinds=kinds,
        length_unit="um",
        angle_unit="urad",
    )
    headers = ["parameter", "value", "2σ", "unit"] + (
        ["true", "error / σ"] if true is not None else []
    )
    rows = []
    for k, p in enumerate(params):
        unit = p.get("unit", "m")
        v, label = _display(values[k], unit)
        row: list[object] = [p["name"], round(v, 3), round(2 * std[k] * 1e6, 3), label]
        if true is not None:
            row += [
                round(true[k] * 1e6, 3),
                round((values[k] - true[k]) / std[k], 2) if std[k] > 0 else "",
            ]
        rows.append(row)
    sections.append(
        Section(
            "Identified parameters",
            "Displacements of the URDF joint origins (lengths in µm, angles in µrad) with "
            "their ±2σ uncertainty"
            + (" and the simulated true values." if true is not None else "."),
            [image],
            [Table(headers, rows)],
        )
    )

    extra_images = []
    if "cost_history" in data:
        extra_images.append(
            plot_convergence(data["cost_history"], plots / "convergence.png", ylabel="½‖r‖²")
        )
    if "index_history" in data:
        extra_images.append(plot_index_history(data["index_history"], plots / "index_history.png"))
    if extra_images:
        sections.append(Section("Convergence and pose selection", "", extra_images))

    files = sorted(p.name for p in src.iterdir() if p.suffix in (".urdf", ".yaml", ".json"))
    if files:
        sections.append(Section("Files", "Calibration output: " + ", ".join(files) + "."))
    return write_report(out_dir, sections, title=f"Calibration report: {data['model']}", name=name)
