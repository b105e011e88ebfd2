"""Plots of a calibration's errors and iteration histories (PNG files), and their drawing.

All plots use matplotlib's Agg canvas directly (no pyplot, no window, no global
state) and are written atomically (temporary file + rename). Values are passed in SI
units (m, rad); a ``unit`` argument chooses the displayed unit: ``m, mm, um (µm),
rad, mrad, urad (µrad), deg``. Matplotlib is imported by the first plot drawn, not
with this module (:mod:`pincal.report._canvas`). Plots of the identified parameters:
:mod:`pincal.report._parameter_plots`.
"""

from __future__ import annotations

import io
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from pincal.errors import ReportError
from pincal.report._canvas import bars as _bars
from pincal.report._canvas import fit_margins, write_png
from pincal.report._canvas import log_scale as _log_scale

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure
    from matplotlib.text import Text

__all__ = [
    "ErrorStats",
    "error_statistics",
    "plot_convergence",
    "plot_error_histogram",
    "plot_errors_before_after",
    "plot_index_history",
    "plot_validation_summary",
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
_BEFORE, AFTER, TRUE = "#d62728", "#1f77b4", "#2ca02c"
_DPI = 110  # PNG pixels per figure inch (the HTML shows them at this size)
_PNG_LEVEL = 1  # zlib level: flat plot colours compress about as well at 1 as at 6, faster


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


# --------------------------------------------------------------------------- helpers


def unit_of(unit: str) -> tuple[float, str]:
    """(scale from metres, label) of a plot unit such as ``um`` or ``mm``."""
    try:
        return _UNITS[unit]
    except KeyError:
        raise ReportError(f"unit {unit!r} not known; units are: {', '.join(_UNITS)}") from None


def checked_vector(values: Sequence[float] | np.ndarray, what: str) -> np.ndarray:
    """``values`` as a finite non-empty 1-D float array, else ReportError naming ``what``."""
    arr = np.asarray(values, dtype=float)
    if arr.ndim != 1 or arr.size == 0:
        raise ReportError(f"{what} must be a non-empty 1-D array (m,), got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ReportError(f"{what} contains NaN or inf")
    return arr


def save_figure(
    fig: Figure,
    path: str | os.PathLike,
    grid: np.ndarray | Sequence[Axes] | Sequence[np.ndarray],
    suptitle: Text | None = None,
) -> Path:
    """Lay out ``grid`` (the figure's axes, (rows, cols)) and write the PNG in one draw."""
    fit_margins(fig, grid, suptitle)
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=_DPI, pil_kwargs={"compress_level": _PNG_LEVEL})
    return write_png(Path(path), buffer.getvalue())


def new_figure(width: float = 7.0, height: float = 4.0) -> Figure:
    """A figure with an Agg canvas and no layout engine (margins: :func:`fit_margins`)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), dpi=_DPI)  # text measured at the saved dpi
    FigureCanvasAgg(fig)
    return fig


def error_statistics(values: Sequence[float] | np.ndarray) -> ErrorStats:
    """RMS, max and mean of ``|values|`` (shape (m,))."""
    arr = np.abs(checked_vector(values, "values"))
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
        title: chart title.
    """
    b = checked_vector(before, "before")
    a = checked_vector(after, "after")
    if a.shape != b.shape:
        raise ReportError(f"before has {b.size} poses but after has {a.size}")
    factor, label = unit_of(unit)
    sb, sa = error_statistics(b * factor), error_statistics(a * factor)
    fig = new_figure()
    ax = fig.add_subplot()
    x = np.arange(b.size)
    _bars(
        ax, x - 0.4, x, np.abs(b) * factor, color=_BEFORE,
        label=f"before: RMS {sb.rms:.4g}, max {sb.max:.4g} {label}",
    )  # fmt: skip
    _bars(
        ax, x, x + 0.4, np.abs(a) * factor, color=AFTER,
        label=f"after: RMS {sa.rms:.4g}, max {sa.max:.4g} {label}",
    )  # fmt: skip
    ax.set_xlabel("pose")
    ax.set_ylabel(f"error [{label}]")
    ax.set_title(title)
    positive = np.abs(np.concatenate([a, b]))
    positive = positive[positive > 0]
    if positive.size and positive.max() > 20 * positive.min():
        _log_scale(ax, "y")  # calibration typically shrinks errors by decades
    if b.size <= 30:
        ax.set_xticks(x)
    fig.legend(loc="lower center", ncol=2, fontsize=8)  # below the axes, not on the bars
    ax.grid(axis="y", alpha=0.3)
    return save_figure(fig, path, [ax])


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
    b = np.abs(checked_vector(before, "before"))
    a = np.abs(checked_vector(after, "after"))
    factor, label = unit_of(unit)
    top = max(b.max(), a.max()) * factor * 1.0001 or 1.0
    low = min(b[b > 0].min(initial=top), a[a > 0].min(initial=top)) * factor
    log_x = top > 50 * low > 0  # before and after decades apart: log bins show both
    edges = np.geomspace(low / 1.0001, top, bins + 1) if log_x else np.linspace(0, top, bins + 1)
    fig = new_figure()
    ax = fig.add_subplot()
    if log_x:
        _log_scale(ax, "x")
    for values, color, side in ((b, _BEFORE, "before"), (a, AFTER, "after")):
        counts, _ = np.histogram(values * factor, edges)
        _bars(
            ax, edges[:-1], edges[1:], counts, color=color, alpha=0.6,
            label=f"{side} (n = {values.size})",
        )  # fmt: skip
    ax.set_xlabel(f"error [{label}]")
    ax.set_ylabel("count")
    ax.set_title(title)
    ax.legend()
    return save_figure(fig, path, [ax])


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
        title: figure title.
    """
    series = dict(history) if isinstance(history, Mapping) else {"index": history}
    if not series:
        raise ReportError("history is empty; expected {name: values per iteration}")
    arrays = {name: checked_vector(v, f"history[{name!r}]") for name, v in series.items()}
    fig = new_figure(7.0, 1.2 + 1.6 * len(arrays))
    axes = fig.subplots(len(arrays), 1, sharex=True, squeeze=False)[:, 0]
    for ax, (name, values) in zip(axes, arrays.items(), strict=True):
        ax.plot(np.arange(values.size), values, "o-", ms=3)
        ax.set_ylabel(name)
        ax.grid(alpha=0.3)
        positive = values > 0
        if positive.all() and values.max() / values.min() > 100:
            _log_scale(ax, "y")
    axes[-1].set_xlabel("iteration")
    axes[0].set_title(title)
    return save_figure(fig, path, axes)


def plot_convergence(
    cost_per_iter: Sequence[float] | np.ndarray,
    path: str | os.PathLike,
    *,
    title: str = "Convergence",
    ylabel: str = "cost",
) -> Path:
    """Cost (e.g. ½‖r‖² or residual RMS) per iteration, shape (iterations,), log scale."""
    cost = checked_vector(cost_per_iter, "cost_per_iter")
    fig = new_figure()
    ax = fig.add_subplot()
    ax.plot(np.arange(cost.size), cost, "o-", ms=4)
    if np.all(cost > 0):
        _log_scale(ax, "y")
    ax.set_xlabel("iteration")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(alpha=0.3, which="both")
    return save_figure(fig, path, [ax])


def plot_validation_summary(
    before: Mapping[str, float | None],
    after: Mapping[str, float | None],
    path: str | os.PathLike,
    *,
    labels: Mapping[str, str] | None = None,
) -> Path:
    """Grouped bars of RMS and max position [mm] / orientation [mrad] errors, before vs after.

    A block whose values are None (not measured) gets no panel; ``labels`` names the
    blocks' axes (e.g. ``{"position": "position (x y)"}``).
    """
    blocks = [(q, u) for q, u in (("position", "mm"), ("orientation", "mrad"))
              if before.get(f"rms_{q}_{u}") is not None] or [("position", "mm")]  # fmt: skip
    fig = new_figure(3.75 * len(blocks) if len(blocks) > 1 else 4.5, 3.6)
    axes = np.atleast_1d(fig.subplots(1, len(blocks)))
    for ax, (quantity, unit) in zip(axes, blocks, strict=True):
        keys = [f"rms_{quantity}_{unit}", f"max_{quantity}_{unit}"]
        b = [float(v) if (v := before.get(k)) is not None else math.nan for k in keys]
        a = [float(v) if (v := after.get(k)) is not None else math.nan for k in keys]
        x = np.arange(2)
        bars_b = ax.bar(x - 0.2, b, 0.4, color=_BEFORE, label="nominal model")
        bars_a = ax.bar(x + 0.2, a, 0.4, color=AFTER, label="calibrated model")
        ax.bar_label(bars_b, fmt="%.3g", fontsize=8)
        ax.bar_label(bars_a, fmt="%.3g", fontsize=8)
        ax.set_xticks(x)
        ax.set_xticklabels(["RMS", "max"])
        ax.set_ylabel(f"{(labels or {}).get(quantity, quantity)} error [{unit}]")
        positive = [v for v in b + a if v > 0]
        if positive and max(positive) / min(positive) > 30:
            _log_scale(ax, "y")
        ax.grid(axis="y", alpha=0.3)
    axes[0].legend(fontsize=8)
    suptitle = fig.suptitle("Validation: predicted vs actual measured-frame pose")
    return save_figure(fig, path, [axes], suptitle)
