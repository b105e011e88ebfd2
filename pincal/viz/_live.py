"""The live view: a meshcat server bound to 127.0.0.1 showing the same scene."""

from __future__ import annotations

import contextlib
import io
import logging
import os
from collections.abc import Sequence
from dataclasses import dataclass

import meshcat
import numpy as np
import pinocchio as pin

from pincal.viz._inputs import Arrow, check_inputs
from pincal.viz._scene import build_scene

__all__ = ["LiveSession", "live"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class LiveSession:
    """A running meshcat server (bound to 127.0.0.1) showing a view.

    Attributes:
        visualizer: the ``meshcat.Visualizer`` (draw more into it if wanted).
        web_url: address to open in a browser.
        zmq_url: address of the server's command socket.
    """

    visualizer: meshcat.Visualizer
    web_url: str
    zmq_url: str

    def close(self) -> None:
        """Stop the server subprocess started for this session."""
        proc = getattr(self.visualizer.window, "server_proc", None)
        if proc is not None and proc.poll() is None:
            proc.kill()
            proc.wait()


def live(
    model: pin.Model,
    urdf_path: str | os.PathLike,
    configurations: Sequence[np.ndarray] | np.ndarray,
    *,
    frame: str | None = None,
    ghosts: bool = True,
    animate: bool = True,
    arrows: Sequence[Arrow | tuple] | None = None,
    arrow_scale: float | None = None,
    ghost_opacity: float = 0.35,
    up: str = "+z",
) -> LiveSession:
    """Start a meshcat server on 127.0.0.1 and draw the same view as :func:`static_html`.

    The server (a subprocess) listens on the loopback interface only; open
    ``session.web_url`` in a local browser and call ``session.close()`` when done
    (it is also stopped when Python exits). Arguments are those of
    :func:`static_html`.
    """
    qs, arrow_list = check_inputs(model, configurations, arrows, arrow_scale, ghost_opacity)
    zmq_url = None
    banner = io.StringIO()
    with contextlib.redirect_stdout(banner):  # meshcat prints the URL; we log it
        vis = meshcat.Visualizer(zmq_url=zmq_url)
    session = LiveSession(vis, vis.window.web_url, vis.window.zmq_url)
    log.info("meshcat viewer at %s", session.web_url)
    try:
        build_scene(
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
            fps=30,
            up=up,
        )
    except BaseException:
        session.close()
        raise
    return session
