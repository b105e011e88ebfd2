"""Reports of a calibration: plots, Markdown and HTML.
"""

from __future__ import annotations

from pincal.report._report import (
    ErrorStats,
    ReportFiles,
    Section,
    Table,
    calibration_report,
    error_statistics,
    plot_convergence,
    plot_error_histogram,
    plot_errors_before_after,
    plot_index_history,
    plot_parameters,
    plot_validation_summary,
    read_identification,
    write_report,
)

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
