"""The offline view: one self-contained HTML page (viewer JavaScript and scene inlined).

:func:`static_html` produces the page without starting meshcat's server: the
meshcat command stream is recorded in-process and replayed by the page, so opening
it needs no server and no network.
"""

from __future__ import annotations

import base64
import html
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import meshcat
import numpy as np
import pinocchio as pin
import umsgpack

from pincal.io import atomic_write_text
from pincal.viz._inputs import Arrow, check_inputs, hex_colour
from pincal.viz._scene import build_scene

__all__ = ["static_html", "write_html"]

_VIEWER_JS = Path(meshcat.__file__).parent / "viewer" / "dist" / "main.min.js"


@dataclass
class _RecordingWindow:
    """Stands in for meshcat's ViewerWindow: records commands instead of sending them."""

    commands: list[bytes] = field(default_factory=list)

    def send(self, command: Any) -> None:
        self.commands.append(umsgpack.packb(command.lower()))


def _legend_html(title: str | None, legend: dict, ghosts: bool, animate: bool) -> str:
    rows = []
    if title:
        rows.append(f"<div class='t'>{html.escape(title)}</div>")
    n = len(legend["poses"])
    if ghosts and n > 1:
        swatches = "".join(
            f"<span class='sw' style='background:#{hex_colour(rgb):06x}'></span>{k}&nbsp;"
            for k, rgb in enumerate(legend["poses"])
        )
        rows.append(f"<div>poses (ghosts): {swatches}</div>")
    if animate and n > 1:
        rows.append(f"<div>opaque copy: animation through the {n} poses</div>")
    if legend["frame"]:
        rows.append(
            f"<div>axes of frame <b>{html.escape(legend['frame'])}</b>: "
            "<span style='color:#d91a1a'>x</span> "
            "<span style='color:#1ab31a'>y</span> "
            "<span style='color:#1a40e6'>z</span></div>"
        )
    if legend.get("up", "+z").lstrip("+") != "z":
        rows.append(f"<div>drawn with world <b>{html.escape(legend['up'])}</b> pointing up</div>")
    if legend.get("grid_cell"):
        rows.append(f"<div>floor grid: {_length_text(legend['grid_cell'])} cells</div>")
    if legend["arrows"]:
        scale = legend["arrow_scale"]
        rows.append(
            f"<div><b>error arrows magnified ×{scale:g}</b> (1 mm drawn as {scale:g} mm)</div>"
        )
        items = [
            f"<span class='sw' style='background:#{hex_colour(rgb):06x}'></span>"
            f"{html.escape(label) + ': ' if label else ''}{1e3 * length:.3f} mm"
            for rgb, label, length in legend["arrows"]
        ]
        if len(items) <= 3:
            rows.extend(f"<div>{item}</div>" for item in items)
        else:  # many arrows: wrap them in one paragraph
            rows.append("<div>" + " ".join(items) + "</div>")
    if not rows:
        return ""
    return "<div id='pincal-legend'>" + "".join(rows) + "</div>"


def _length_text(metres: float) -> str:
    if metres >= 1.0:
        return f"{metres:g} m"
    if metres >= 1e-3:
        return f"{1e3 * metres:g} mm"
    return f"{1e6 * metres:g} µm"


_PAGE = """<!DOCTYPE html>
<html>
<head>
<meta charset="utf-8">
<title>{title}</title>
<style>
body {{ margin: 0; overflow: hidden; }}
#meshcat-pane {{ width: 100vw; height: 100vh; overflow: hidden; }}
#pincal-legend {{ position: absolute; left: 8px; top: 8px; max-width: 45vw;
  background: rgba(255, 255, 255, 0.85); border-radius: 4px; padding: 6px 9px;
  font: 13px/1.45 sans-serif; color: #222; }}
#pincal-legend .t {{ font-weight: bold; font-size: 15px; }}
#pincal-legend .sw {{ display: inline-block; width: 11px; height: 11px;
  margin: 0 3px 0 4px; border: 1px solid #555; vertical-align: -1px; }}
</style>
</head>
<body>
<div id="meshcat-pane"></div>
{legend}
<script>
{viewer_js}
</script>
<script>
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
var pincalScene = [
{commands}
];
for (var i = 0; i < pincalScene.length; i++) {{
  var raw = atob(pincalScene[i]);
  var bytes = new Uint8Array(raw.length);
  for (var j = 0; j < raw.length; j++) {{ bytes[j] = raw.charCodeAt(j); }}
  viewer.handle_command_bytearray(bytes);
}}
</script>
</body>
</html>
"""


def static_html(
    model: pin.Model,
    urdf_path: str | os.PathLike,
    configurations: Sequence[np.ndarray] | np.ndarray,
    *,
    frame: str | None = None,
    ghosts: bool = True,
    animate: bool = True,
    arrows: Sequence[Arrow | tuple] | None = None,
    arrow_scale: float | None = None,
    title: str | None = None,
    ghost_opacity: float = 0.35,
    fps: int = 30,
    up: str = "+z",
    allow_mesh_outside: bool = False,
    progress: Callable[[int, int], None] | None = None,
) -> str:
    """A self-contained HTML page showing ``model`` at ``configurations``.

    Args:
        model: the Pinocchio model, built from ``urdf_path`` (possibly with changed
            placements, e.g. a calibrated model; link names must match).
        urdf_path: the URDF file (its ``<visual>`` elements are drawn; ``package://``
            URIs resolve against the file's ancestor folders) or the URDF XML text.
            Mesh files are read only from inside the URDF's directory (or the
            ``package://`` package holding the URDF) and embedded in the page.
        configurations: sequence of configurations, each shape (model.nq,).
        frame: name of a model frame (the measured frame) whose axes are drawn at
            every configuration, or None.
        ghosts: draw one semi-transparent copy per configuration.
        animate: add an opaque copy looping through the configurations (ignored
            for a single configuration).
        arrows: error arrows, each an :class:`Arrow` or ``(start (3,), end (3,),
            colour, label)`` in the world frame [m].
        arrow_scale: magnification of the arrows; None picks a 1-2-5 value making
            the longest about 30 % of the scene. The legend states it.
        title: page title and legend heading.
        ghost_opacity: opacity of ghost copies in [0, 1].
        fps: animation frame rate.
        up: the world direction drawn pointing up: ``+z`` (default), ``-z`` (a
            machine whose world z points down, towards the table), ``±x``, ``±y``.
        allow_mesh_outside: also read meshes outside the model's directory (absolute
            paths, ``../``): their bytes end up in the page, so only for trusted URDFs.
        progress: optional callback ``(done, total)`` while the scene is built
            (each pose, then each animation segment).

    Returns:
        The HTML text (a few MB: meshcat's viewer is inlined). Opening it needs no
        server and no network.

    Raises:
        VisualizationError: malformed configurations, arrows or colours; a mesh outside
            the model's directory, a mesh URL, a missing or unreadable mesh file.
        UnknownNameError: ``frame`` is not a frame of ``model``.
        ModelFileError: the URDF file does not exist.
    """
    qs, arrow_list = check_inputs(model, configurations, arrows, arrow_scale, ghost_opacity)
    window = _RecordingWindow()
    vis = meshcat.Visualizer(window=window)
    legend = build_scene(
        vis,
        model,
        urdf_path,
        qs,
        frame=frame,
        ghosts=ghosts,
        animate=animate,
        arrows=arrow_list,
        arrow_scale=arrow_scale,
        ghost_opacity=ghost_opacity,
        fps=fps,
        up=up,
        allow_mesh_outside=allow_mesh_outside or None,
        progress=progress,
    )
    commands = ",\n".join('"' + base64.b64encode(c).decode("ascii") + '"' for c in window.commands)
    return _PAGE.format(
        title=html.escape(title or "pincal view"),
        legend=_legend_html(title, legend, ghosts, animate and len(qs) > 1),
        viewer_js=_VIEWER_JS.read_text(encoding="utf-8"),
        commands=commands,
    )


def write_html(path: str | os.PathLike, html_text: str) -> Path:
    """Write ``html_text`` to ``path`` atomically (temporary file + rename); returns the path."""
    return atomic_write_text(Path(path), html_text)
