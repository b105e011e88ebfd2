"""Axis helpers of the report plots: log axes labelled without mathtext."""

from __future__ import annotations

import re

from matplotlib.axes import Axes
from matplotlib.ticker import LogFormatterSciNotation

__all__ = ["log_scale"]

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


def log_scale(ax: Axes, which: str) -> None:
    """Log scale on the ``"x"`` or ``"y"`` axis, labelled in plain text (_PlainLogFormatter)."""
    if which == "x":
        ax.set_xscale("log")
    else:
        ax.set_yscale("log")
    axis = ax.xaxis if which == "x" else ax.yaxis
    axis.set_major_formatter(_PlainLogFormatter(10.0))
    axis.set_minor_formatter(_PlainLogFormatter(10.0, labelOnlyBase=False))
