"""Axes helpers of the report plots: log axes labelled without mathtext, cheap bars."""

from __future__ import annotations

import re
from collections.abc import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.collections import PolyCollection
from matplotlib.ticker import LogFormatterSciNotation, LogLocator

__all__ = ["bars", "log_scale"]

_SUPERSCRIPT = str.maketrans("0123456789-", "⁰¹²³⁴⁵⁶⁷⁸⁹⁻")
_MATHTEXT = re.compile(r"^\$\\mathdefault\{(.*)\}\$$")
_POWER = re.compile(r"\^\{(-?\d+)\}")


class _PlainLogFormatter(LogFormatterSciNotation):
    """Matplotlib's log-axis labels (10³, 2×10⁻¹) as plain Unicode text.

    Same ticks and the same labelling rules as the default formatter; the labels are
    drawn as ordinary text instead of mathtext, whose parser costs ~10 ms per label.
    """

    def __call__(self, x: float, pos: int | None = None) -> str:
        label = super().__call__(x, pos)
        match = _MATHTEXT.match(label)
        if match is None:
            return label
        body = match.group(1).replace("\\times", "×")
        return _POWER.sub(lambda m: m.group(1).translate(_SUPERSCRIPT), body).replace("-", "−")


class _InViewLogLocator(LogLocator):
    """Matplotlib's log-axis minor ticks, without those outside the view.

    The default locator also returns the ticks of the partial decades beyond both
    ends of the axis, which are never drawn but each cost a tick object (five
    artists) per plot; the drawn ticks are the same.
    """

    def __call__(self) -> Sequence[float]:
        locs = np.asarray(super().__call__(), dtype=float)
        if self.axis is None:
            return list(locs)
        lo, hi = sorted(self.axis.get_view_interval())
        return list(locs[(locs >= lo * (1 - 1e-10)) & (locs <= hi * (1 + 1e-10))])


def log_scale(ax: Axes, which: str) -> None:
    """Log scale on the ``"x"`` or ``"y"`` axis, labelled in plain text (_PlainLogFormatter)."""
    if which == "x":
        ax.set_xscale("log")
    else:
        ax.set_yscale("log")
    axis = ax.xaxis if which == "x" else ax.yaxis
    axis.set_minor_locator(_InViewLogLocator(10.0, None))  # as LogScale sets it
    axis.set_major_formatter(_PlainLogFormatter(10.0))
    axis.set_minor_formatter(_PlainLogFormatter(10.0, labelOnlyBase=False))


def bars(
    ax: Axes,
    left: np.ndarray,
    right: np.ndarray,
    heights: np.ndarray,
    *,
    color: str,
    label: str,
    alpha: float | None = None,
) -> PolyCollection:
    """Bars from 0 to ``heights`` over [left, right] (shapes (m,)), drawn as one artist.

    Looks like :meth:`Axes.bar` (filled, no edge, y = 0 sticky so a linear axis starts
    at 0, one legend entry) but is one collection instead of m patches, which matters
    for the tens of bars per plot of a report.
    """
    x0, x1, h = (np.asarray(v, dtype=float) for v in (left, right, heights))
    zero = np.zeros_like(h)
    verts = np.stack(
        [
            np.stack([x0, zero], 1),
            np.stack([x0, h], 1),
            np.stack([x1, h], 1),
            np.stack([x1, zero], 1),
        ],
        axis=1,
    )
    coll = PolyCollection(
        list(verts), facecolors=color, edgecolors="none", linewidths=0.0, alpha=alpha, label=label
    )
    coll.sticky_edges.y.append(0.0)
    ax.add_collection(coll, autolim=True)
    ax.autoscale_view()
    return coll
