"""Meshcat views of a mechanism: offline static HTML and a live local session.

Modules: ``_inputs`` (checked configurations, arrows, colours, up direction),
``_geometry`` (parts from URDF visuals and meshes, skeleton sticks), ``_drawing``
(meshcat primitives: parts, triads, arrows, grid, camera), ``_scene`` (ghosts,
animation and arrows of one view), ``_html`` (the offline page) and ``_live`` (the
meshcat server session). meshcat is imported only when this package is.
"""

from __future__ import annotations

from pincal.viz._html import (
    static_html,
    write_html,
)
from pincal.viz._inputs import (
    Arrow,
)
from pincal.viz._live import (
    LiveSession,
    live,
)
from pincal.viz._meshes import (
    allow_mesh_outside,
)

__all__ = [
    "Arrow",
    "LiveSession",
    "allow_mesh_outside",
    "live",
    "static_html",
    "write_html",
]
