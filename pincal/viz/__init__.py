"""Meshcat views of a mechanism: offline static HTML and a live local session.
"""

from __future__ import annotations

from pincal.viz._viz import (
    Arrow,
    LiveSession,
    live,
    static_html,
    write_html,
)

__all__ = [
    "Arrow",
    "LiveSession",
    "live",
    "static_html",
    "write_html",
]
