"""The matplotlib side of the report plots, imported by the first plot drawn.

Importing matplotlib (with its Agg backend, fonts and PIL for the PNG) costs about
0.3 s. ``import pincal.report`` does not pay it: the plot functions import it when
they draw, so a process that writes no plot never imports it.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from pincal.io import atomic_write_bytes

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.collections import PolyCollection
    from matplotlib.figure import Figure
    from matplotlib.text import Text

__all__ = [
    "bars",
    "fit_margins",
    "import_matplotlib",
    "log_scale",
    "scratch_files",
    "write_png",
]

_SCRATCH: ContextVar[bool] = ContextVar("pincal_report_scratch", default=False)


@contextmanager
def scratch_files() -> Iterator[None]:
    """Within this context :func:`write_png` writes without fsync.

    For plots drawn into a private temporary folder, read back and deleted (a
    report's plots): durability buys nothing there and costs a few ms per file.
    """
    token = _SCRATCH.set(True)
    try:
        yield
    finally:
        _SCRATCH.reset(token)


def write_png(path: Path, data: bytes) -> Path:
    """Write a plot's bytes to ``path`` atomically (without fsync in :func:`scratch_files`)."""
    return atomic_write_bytes(path, data, durable=not _SCRATCH.get())


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
    """:func:`pincal.report._axes.bars` (bars from 0 to ``heights``, shapes (m,))."""
    from pincal.report._axes import bars as draw

    return draw(ax, left, right, heights, color=color, label=label, alpha=alpha)


def log_scale(ax: Axes, which: str) -> None:
    """:func:`pincal.report._axes.log_scale` (log ``"x"`` or ``"y"`` axis, plain labels)."""
    from pincal.report._axes import log_scale as scale

    scale(ax, which)


def fit_margins(
    fig: Figure,
    axes: np.ndarray | Sequence[Axes] | Sequence[np.ndarray],
    suptitle: Text | None = None,
) -> None:
    """:func:`pincal.report._layout.fit_margins` (margins sized to the labels)."""
    from pincal.report._layout import fit_margins as fit

    fit(fig, axes, suptitle)


def import_matplotlib() -> None:
    """Import the matplotlib modules the plots use (Agg canvas, figure, axes helpers)."""
    import matplotlib.backends.backend_agg
    import matplotlib.figure  # noqa: F401

    import pincal.report._axes
    import pincal.report._layout  # noqa: F401

