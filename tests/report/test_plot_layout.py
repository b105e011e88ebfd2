"""Report plots are laid out in one pass (no constrained layout, no extra draw): the PNG
keeps its pixel size and nothing sticks out of the figure or into a neighbouring panel."""

from __future__ import annotations

import struct

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import LogLocator

from pincal.report import _parameter_plots, _plots
from pincal.report._axes import log_scale
from pincal.report._layout import fit_margins

LONG = [f"platform_p{i}_joint_with_a_long_name.t{'xyz'[i % 3]}" for i in range(14)]


def _png_size(path) -> tuple[int, int]:
    head = path.read_bytes()[:24]
    assert head[:8] == b"\x89PNG\r\n\x1a\n"
    return struct.unpack(">II", head[16:24])


def _assert_nothing_clipped(fig: Figure) -> None:
    """Every axes' drawn decorations inside the figure; none over another axes' box."""
    renderer = fig.canvas.get_renderer()
    page = fig.bbox
    for ax in fig.axes:
        tight = ax.get_tightbbox(renderer)
        assert tight.x0 >= page.x0 - 1 and tight.y0 >= page.y0 - 1, ax
        assert tight.x1 <= page.x1 + 1 and tight.y1 <= page.y1 + 1, ax
        for other in fig.axes:
            if other is ax or other in ax.child_axes:
                continue
            box = other.bbox
            overlap_x = min(tight.x1, box.x1) - max(tight.x0, box.x0)
            overlap_y = min(tight.y1, box.y1) - max(tight.y0, box.y0)
            assert min(overlap_x, overlap_y) <= 1, (ax, other)
    for text in [*fig.legends, *fig.texts]:
        box = text.get_window_extent(renderer)
        assert page.x0 - 1 <= box.x0 and box.x1 <= page.x1 + 1, text
        assert page.y0 - 1 <= box.y0 and box.y1 <= page.y1 + 1, text


@pytest.fixture
def figures(monkeypatch):
    """The figures the plot functions save, kept for inspection."""
    kept: list[Figure] = []

    def keep(fig, grid, suptitle=None):
        kept.append(fig)
        fit_margins(fig, grid, suptitle)

    monkeypatch.setattr(_plots, "fit_margins", keep)
    return kept


def _draw_every_plot(tmp_path):
    rng = np.random.default_rng(3)
    before, after = rng.uniform(1e-3, 2e-3, 40), rng.uniform(1e-6, 3e-5, 40)
    cov = np.cov(rng.normal(size=(len(LONG), 60)))
    std = np.sqrt(np.diag(cov)) * 1e-4
    return [
        (_plots.plot_errors_before_after(before, after, "um", tmp_path / "a.png"), (7.0, 4.0)),
        (_plots.plot_error_histogram(before, after, "um", tmp_path / "b.png"), (7.0, 4.0)),
        (_plots.plot_index_history({"O1": [1, 3, 5.0], "O3": [1e-4, 1e-1, 2]}, tmp_path / "c.png"),
         (7.0, 1.2 + 1.6 * 2)),
        (_plots.plot_convergence([1e6, 1e3, 50, 49], tmp_path / "d.png"), (7.0, 4.0)),
        (_parameter_plots.plot_parameters(LONG, std, std, std * 0.5, tmp_path / "e.png",
                                kinds=["length", "angle"] * 7),
         (7.5, max(3.0, 1.5 + 0.22 * len(LONG) + 0.6 * 2))),
        (_plots.plot_validation_summary(
            {"rms_position_mm": 1.4, "max_position_mm": 2.0, "rms_orientation_mrad": 11.0,
             "max_orientation_mrad": 13.0},
            {"rms_position_mm": 0.01, "max_position_mm": 0.02, "rms_orientation_mrad": 0.014,
             "max_orientation_mrad": 0.03}, tmp_path / "f.png"), (7.5, 3.6)),
        (_parameter_plots.plot_correlation(LONG, cov, tmp_path / "g.png"),
         (3.0 + 0.18 * len(LONG) + 1.2, 3.0 + 0.18 * len(LONG))),
    ]  # fmt: skip


def test_plots_keep_their_pixel_size(tmp_path):
    for path, (width, height) in _draw_every_plot(tmp_path):
        assert _png_size(path) == (int(width * 110), int(height * 110)), path.name


def test_no_label_is_clipped_or_over_a_neighbour(tmp_path, figures):
    _draw_every_plot(tmp_path)
    assert len(figures) == 7
    for fig in figures:
        assert fig.get_layout_engine() is None  # one draw per figure, at savefig
        _assert_nothing_clipped(fig)


def test_default_margins_would_clip_these_labels():
    """The check above can fail: matplotlib's default margins cut long tick labels."""
    fig = Figure(figsize=(7.0, 4.0))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.set_yticks(range(len(LONG)), LONG)
    ax.set_xlabel("length [µm]")
    fig.canvas.draw()
    with pytest.raises(AssertionError):
        _assert_nothing_clipped(fig)
    fit_margins(fig, [ax])
    fig.canvas.draw()
    _assert_nothing_clipped(fig)


def _log_plot_png(minor_locator) -> bytes:
    import io

    fig = Figure(figsize=(4.0, 3.0), dpi=80)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.plot([1, 2, 3], [3.0, 40.0, 2000.0])
    log_scale(ax, "y")
    if minor_locator is not None:
        ax.yaxis.set_minor_locator(minor_locator)
    ax.grid(which="both")
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png")
    return buffer.getvalue()


def test_log_minor_ticks_outside_the_view_are_not_made_and_the_plot_is_the_same():
    fig = Figure()
    ax = fig.add_subplot()
    ax.set_ylim(3.0, 2000.0)
    log_scale(ax, "y")
    locs = ax.yaxis.get_minorticklocs()
    assert locs.min() >= 3.0 and locs.max() <= 2000.0
    assert len(locs) < len(LogLocator(10.0, None).tick_values(3.0, 2000.0))
    assert _log_plot_png(None) == _log_plot_png(LogLocator(10.0, None))


def test_labels_wider_than_the_figure_still_give_a_plot(tmp_path):
    names = ["x" * 300 + str(i) for i in range(3)]
    path = _parameter_plots.plot_parameters(
        names, [1e-4] * 3, [1e-5] * 3, path=tmp_path / "wide.png"
    )
    assert _png_size(path) == (int(7.5 * 110), int(3.0 * 110))
