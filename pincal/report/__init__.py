"""Reports of a calibration.

Plots, Markdown and HTML, the report of a calibration output directory (read from its
``identification.json``) and the plain texts `pincal calibrate` (``report.txt``) and
`pincal validate` print.
"""

from __future__ import annotations

from pincal.report._calibration import calibration_report
from pincal.report._campaign_notes import campaign_notes
from pincal.report._cv_text import cross_validation_text
from pincal.report._document import ReportFiles, Section, Table, write_report
from pincal.report._fleet import fleet_html, fleet_markdown, plot_fleet
from pincal.report._marker_text import marker_lines
from pincal.report._parameter_plots import plot_parameters
from pincal.report._plots import (
    ErrorStats,
    error_statistics,
    plot_convergence,
    plot_error_histogram,
    plot_errors_before_after,
    plot_index_history,
    plot_validation_summary,
)
from pincal.report._sections import block_label
from pincal.report._text import calibration_text, quality_lines
from pincal.report._transfer_text import transfer_text
from pincal.report._validation_text import marker_errors_text, validation_text

__all__ = [
    "ErrorStats",
    "ReportFiles",
    "Section",
    "Table",
    "block_label",
    "calibration_report",
    "calibration_text",
    "campaign_notes",
    "cross_validation_text",
    "error_statistics",
    "fleet_html",
    "fleet_markdown",
    "marker_errors_text",
    "marker_lines",
    "plot_convergence",
    "plot_error_histogram",
    "plot_errors_before_after",
    "plot_fleet",
    "plot_index_history",
    "plot_parameters",
    "plot_validation_summary",
    "quality_lines",
    "transfer_text",
    "validation_text",
    "write_report",
]
