"""Margins of a report figure sized to its labels, in one pass and without a draw.

Matplotlib's constrained layout (and ``tight_layout``) find the margins by measuring
every axes' tight bounding box, which updates all ticks several times and, with
constrained layout, costs a whole extra draw at ``savefig``: about half the time of a
report plot. The report's figures are simple grids (one column of panels, or one row),
so :func:`fit_margins` measures only what sticks out of each axes — tick labels, axis
labels, titles, offset texts, a figure legend at the bottom, the suptitle — as text
extents, and places the grid with :meth:`Figure.subplots_adjust`. The figure size (so
the PNG's pixel size) does not change.
"""

from __future__ import annotations

from collections.abc import Sequence

import matplotlib as mpl
import numpy as np
from matplotlib.axes import Axes
from matplotlib.axis import Axis
from matplotlib.backend_bases import RendererBase
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.text import Text

__all__ = ["fit_margins"]

_BORDER = 0.06  # inches of white space kept at the figure edge
_GAP = 0.06  # inches between an axes' decorations and its neighbour's


def _inches(fig: Figure, pixels: float) -> float:
    return float(pixels) / fig.dpi


def _tick_labels(axis: Axis) -> list[tuple[Text, int]]:
    """(label, 1 or 2) of the visible, non-empty tick labels of ticks in the view interval."""
    lo, hi = sorted(axis.get_view_interval())
    slack = 1e-10 * (hi - lo)
    axis.get_majorticklabels()  # places the major and minor ticks and sets their label texts
    labels = []
    for ticks, locs in (
        (axis.get_major_ticks(), axis.get_majorticklocs()),
        (axis.get_minor_ticks(), axis.get_minorticklocs()),
    ):
        for tick, loc in zip(ticks, locs, strict=False):
            if lo - slack <= loc <= hi + slack:
                labels += [(label, k) for k, label in ((1, tick.label1), (2, tick.label2))]
    return [(label, k) for label, k in labels if label.get_visible() and label.get_text()]


def _text_size(fig: Figure, renderer: RendererBase, text: Text) -> tuple[float, float]:
    """Width and height [in] of a Text artist as drawn (rotation included)."""
    if not text.get_visible() or not text.get_text():
        return 0.0, 0.0
    box = text.get_window_extent(renderer)
    return _inches(fig, box.width), _inches(fig, box.height)


def _tick_room(which: str) -> float:
    """Tick length + label pad [in] of the major ticks of ``axis`` (``"x"`` or ``"y"``)."""
    if which == "x":
        size = mpl.rcParams["xtick.major.size"] + mpl.rcParams["xtick.major.pad"]
    else:
        size = mpl.rcParams["ytick.major.size"] + mpl.rcParams["ytick.major.pad"]
    return float(size) / 72.0


def _decorations(fig: Figure, renderer: RendererBase, ax: Axes) -> dict[str, float]:
    """Inches that ``ax``'s labels need outside the axes box on each side."""
    need = dict.fromkeys(("left", "right", "bottom", "top"), 0.0)
    for axis, which in ((ax.xaxis, "x"), (ax.yaxis, "y")):
        sides = ("left", "right") if which == "y" else ("bottom", "top")
        for label, k in _tick_labels(axis):
            w, h = _text_size(fig, renderer, label)
            side = sides[k - 1]
            need[side] = max(need[side], (w if which == "y" else h) + _tick_room(which))
            for end in ("bottom", "top") if which == "y" else ("left", "right"):
                need[end] = max(need[end], (h if which == "y" else w) / 2)  # end labels stick out
        label = axis.get_label()
        if label.get_visible() and label.get_text():
            w, h = _text_size(fig, renderer, label)
            side = axis.get_label_position()
            pad = axis.labelpad / 72.0
            need[side] += (w if which == "y" else h) + pad
        offset = axis.get_offset_text()
        if offset.get_visible() and offset.get_text():
            _, h = _text_size(fig, renderer, offset)
            need["top" if which == "y" else "bottom"] += h
    if ax.get_title():
        _, h = _text_size(fig, renderer, ax.title)
        need["top"] = max(need["top"], h + mpl.rcParams["axes.titlepad"] / 72.0)
    return need


def fit_margins(
    fig: Figure,
    axes: np.ndarray | Sequence[Axes] | Sequence[np.ndarray],
    suptitle: Text | None = None,
) -> None:
    """Place the grid of ``axes`` (shape (rows, cols)) with margins sized to its labels.

    Extra axes attached to a grid cell (a colorbar) count on the side where they sit.

    Args:
        fig: the figure (an Agg canvas is attached if it has none).
        axes: the grid's axes, shape (rows, cols) (or (rows,): one column).
        suptitle: the figure's suptitle, if it has one.
    """
    grid = np.asarray(axes, dtype=object)
    grid = grid.reshape(grid.shape[0], -1)
    canvas = fig.canvas if isinstance(fig.canvas, FigureCanvasAgg) else FigureCanvasAgg(fig)
    renderer = canvas.get_renderer()
    width, height = fig.get_size_inches()
    needs = {ax: _decorations(fig, renderer, ax) for ax in fig.axes}
    rows, cols = grid.shape
    extra = [ax for ax in fig.axes if ax not in set(grid.ravel())]
    left = max(needs[ax]["left"] for ax in grid[:, 0])
    bottom = max(needs[ax]["bottom"] for ax in grid[-1, :])
    top = max(needs[ax]["top"] for ax in grid[0, :])
    right = max([needs[ax]["right"] for ax in grid[:, -1]] + [needs[ax]["right"] for ax in extra])
    if suptitle is not None:
        top += _text_size(fig, renderer, suptitle)[1] + _GAP
    for legend in fig.legends:
        bottom += _inches(fig, legend.get_window_extent(renderer).height) + _GAP
    left, bottom, top, right = (v + _BORDER for v in (left, bottom, top, right))
    hgap = max(
        [needs[ax]["bottom"] + needs[below]["top"] for ax, below in zip(
            grid[:-1].ravel(), grid[1:].ravel(), strict=True)] or [0.0]
    ) + _GAP  # fmt: skip
    wgap = max(
        [needs[ax]["right"] + needs[nxt]["left"] for ax, nxt in zip(
            grid[:, :-1].ravel(), grid[:, 1:].ravel(), strict=True)] or [0.0]
    ) + _GAP  # fmt: skip
    # labels too big for the figure: shrink the margins so the axes keep 30 % of it (the
    # labels are then cut, as with any layout engine, but the plot is still drawn)
    shrink_h = min(1.0, 0.7 * height / (bottom + top + (rows - 1) * hgap))
    shrink_w = min(1.0, 0.7 * width / (left + right + (cols - 1) * wgap))
    bottom, top, hgap = (v * shrink_h for v in (bottom, top, hgap))
    left, right, wgap = (v * shrink_w for v in (left, right, wgap))
    axes_h = (height - bottom - top - (rows - 1) * hgap) / rows
    axes_w = (width - left - right - (cols - 1) * wgap) / cols
    fig.subplots_adjust(
        left=left / width,
        right=1.0 - right / width,
        bottom=bottom / height,
        top=1.0 - top / height,
        hspace=hgap / axes_h,
        wspace=wgap / axes_w,
    )
