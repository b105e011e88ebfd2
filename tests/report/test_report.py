"""Tests of pincal.report: plot files, statistics and the assembled report."""

from __future__ import annotations

import struct

import numpy as np
import pytest

import pincal.errors
from pincal import report


def _png_size(path) -> tuple[int, int]:
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", f"{path} is not a PNG"
    assert data[12:16] == b"IHDR"
    width, height = struct.unpack(">II", data[16:24])
    return width, height


def _assert_plot(path, min_bytes: int = 8000) -> None:
    assert path.is_file()
    width, height = _png_size(path)
    assert width >= 300 and height >= 200
    assert path.stat().st_size > min_bytes  # axes, bars and text, not an empty canvas
    assert not list(path.parent.glob(".*.tmp"))


@pytest.fixture()
def errors():
    rng = np.random.default_rng(3)
    before = np.abs(rng.normal(0.0, 2e-3, 18))  # [m]
    after = np.abs(rng.normal(0.0, 2e-4, 18))
    return before, after


def test_error_statistics_against_numpy():
    values = np.array([3.0, -4.0, 0.0, 1.0])
    stats = report.error_statistics(values)
    assert stats.rms == pytest.approx(np.sqrt((9 + 16 + 0 + 1) / 4))
    assert stats.max == 4.0 and stats.mean == pytest.approx(2.0) and stats.count == 4


def test_plots_are_written(tmp_path, errors):
    before, after = errors
    paths = [
        report.plot_errors_before_after(before, after, "mm", tmp_path / "before_after.png"),
        report.plot_error_histogram(before, after, "um", tmp_path / "hist.png"),
        report.plot_convergence([1.0, 1e-2, 1e-5, 1e-9, 1e-12], tmp_path / "conv.png"),
        report.plot_index_history(
            {"O1": np.linspace(1, 3, 12), "O3": np.geomspace(1e-4, 1e-2, 12)},
            tmp_path / "index.png",
        ),
    ]
    for path in paths:
        _assert_plot(path)


def test_parameter_plot_splits_lengths_and_angles(tmp_path):
    names = ["leg1.tx", "leg1.ty", "leg1.tz", "leg1.rx", "leg2_slide.offset"]
    values = np.array([1e-4, -2e-4, 5e-5, 1e-3, 3e-5])
    std = np.array([1e-5, 1e-5, 2e-5, 1e-4, 1e-5])
    true = values + np.array([5e-6, -5e-6, 0.0, 5e-5, 0.0])
    one = report.plot_parameters(names, values, std, true, tmp_path / "p.png")
    _assert_plot(one)
    lengths_only = report.plot_parameters(names[:3], values[:3], std[:3], path=tmp_path / "l.png")
    # two panels make the figure taller than the one-panel version
    assert _png_size(one)[1] > _png_size(lengths_only)[1]


def test_bad_inputs(tmp_path):
    with pytest.raises(pincal.errors.ReportError, match="after has 2"):
        report.plot_errors_before_after([1, 2, 3], [1, 2], "mm", tmp_path / "x.png")
    with pytest.raises(pincal.errors.ReportError, match="units are"):
        report.plot_errors_before_after([1, 2], [1, 2], "inch", tmp_path / "x.png")
    with pytest.raises(pincal.errors.ReportError, match="NaN"):
        report.plot_convergence([1.0, float("nan")], tmp_path / "x.png")
    with pytest.raises(pincal.errors.ReportError, match="3 names"):
        report.plot_parameters(["a.tx", "b.tx", "c.tx"], [1, 2], [1, 1], path=tmp_path / "x.png")
    assert not (tmp_path / "x.png").exists()


def test_report_references_plots_and_tables(tmp_path, errors):
    before, after = errors
    plot = report.plot_errors_before_after(before, after, "mm", tmp_path / "img" / "errors.png")
    stats_before = report.error_statistics(before * 1e3)
    table = report.Table(
        headers=["", "RMS [mm]", "max [mm]"],
        rows=[["before", stats_before.rms, stats_before.max], ["after|x", 0.1, 0.2]],
        caption="Validation poses",
    )
    files = report.write_report(
        tmp_path,
        [
            report.Section("Errors", text="Position error at 18 poses.", images=[plot]),
            report.Section("Summary", tables=[table]),
        ],
        title="Stewart <test>",
    )
    md = files.markdown.read_text()
    page = files.html.read_text()
    assert "![errors](img/errors.png)" in md
    assert '<img src="data:image/png;base64,' in page  # self-contained page
    assert f"{stats_before.rms:.6g}" in md and f"{stats_before.rms:.6g}" in page
    assert "after\\|x" in md  # a pipe in a cell does not break the Markdown table
    assert "Stewart &lt;test&gt;" in page and "<caption>Validation poses</caption>" in page
    with pytest.raises(pincal.errors.ReportError, match="not found"):
        report.write_report(tmp_path, [report.Section("x", images=["missing.png"])])
