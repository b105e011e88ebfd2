"""The live view: a meshcat server bound to 127.0.0.1 showing the same scene.

meshcat's own launcher listens on every interface (0.0.0.0 and [::]) and leaves its
server running when Python is killed. Here pincal starts the server itself: its web
and command sockets bind one address (127.0.0.1 unless asked), the server is in
pincal's process group (Ctrl-C reaches both), is stopped by :meth:`LiveSession.close`
and at interpreter exit, and on Linux the kernel kills it when pincal dies, even by
SIGKILL (``PR_SET_PDEATHSIG``); elsewhere it exits within a second of noticing its
parent is gone.
"""

from __future__ import annotations

import atexit
import contextlib
import ctypes
import io
import ipaddress
import logging
import os
import signal
import subprocess
import sys
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import meshcat
import numpy as np
import pinocchio as pin

from pincal.errors import VisualizationError, clip
from pincal.viz._inputs import Arrow, check_inputs
from pincal.viz._scene import build_scene

__all__ = ["LiveSession", "live"]

log = logging.getLogger(__name__)

#: the meshcat server, run with ``python -c``: argv = host, parent pid
_SERVER = """
import os, sys
import tornado.ioloop, tornado.web
host, parent = sys.argv[1], int(sys.argv[2])
_listen = tornado.web.Application.listen
def _bound(self, port, address=None, **kw):
    return _listen(self, port, host if address is None else address, **kw)
tornado.web.Application.listen = _bound
from meshcat.servers.zmqserver import ZMQWebSocketBridge
bridge = ZMQWebSocketBridge(host=host)
print("zmq_url=" + bridge.zmq_url, flush=True)
print("web_url=" + bridge.web_url, flush=True)
def _orphaned():
    if os.getppid() != parent:
        os._exit(0)
tornado.ioloop.PeriodicCallback(_orphaned, 500).start()
bridge.run()
"""


def _die_with(parent: int) -> Callable[[], None]:
    """``preexec_fn`` of the server: killed with its parent (Linux), gone if already."""

    def arm() -> None:
        if sys.platform.startswith("linux"):
            pr_set_pdeathsig = 1
            ctypes.CDLL(None, use_errno=True).prctl(pr_set_pdeathsig, int(signal.SIGKILL))
        if os.getppid() != parent:
            os._exit(0)

    return arm


def _check_host(host: str) -> str:
    try:
        addr = ipaddress.ip_address(host)
    except ValueError:
        addr = None
    if addr is None or addr.version != 4:
        raise VisualizationError(
            f"--host {clip(host)} is not an IPv4 address; give 127.0.0.1 (loopback, the "
            f"default) or the address of one local interface (0.0.0.0: every interface)"
        )
    if not addr.is_unspecified:  # an address no interface holds fails here, not port by port
        import socket

        with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
            try:
                probe.bind((str(addr), 0))
            except OSError as exc:
                raise VisualizationError(
                    f"--host {clip(host)} is not an address of this machine ({exc.strerror}); "
                    "give 127.0.0.1 (loopback, the default), the address of one local "
                    "interface, or 0.0.0.0 (every interface)"
                ) from None
    if not addr.is_loopback:
        log.warning("the meshcat server listens on %s: reachable from other machines", host)
    return str(addr)


def _start_server(host: str) -> tuple[subprocess.Popen, str, str]:
    """Start the meshcat server bound to ``host``; returns (process, zmq url, web url)."""
    errors = tempfile.TemporaryFile()  # not a pipe: a chatty server never blocks on it
    proc = subprocess.Popen(
        [sys.executable, "-u", "-c", _SERVER, host, str(os.getpid())],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=errors,
        preexec_fn=_die_with(os.getpid()),
    )
    atexit.register(_stop, proc)
    urls: dict[str, str] = {}
    assert proc.stdout is not None
    with errors:  # the child keeps its own descriptor
        while len(urls) < 2:
            line = proc.stdout.readline().decode("utf-8", "replace").strip()
            if not line:
                _stop(proc)
                errors.seek(0)
                err = errors.read(1 << 16).decode("utf-8", "replace")
                last = err.strip().splitlines()[-1:] or ["no output"]
                raise VisualizationError(
                    f"the meshcat server did not start on {host}: {clip(last[0], 200)}"
                )
            key, _, value = line.partition("=")
            if key in ("zmq_url", "web_url"):
                urls[key] = value
    proc.stdout.close()
    return proc, urls["zmq_url"], urls["web_url"]


def _stop(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        proc.kill()
        proc.wait()
    if proc.stdout is not None:
        proc.stdout.close()


@dataclass(frozen=True)
class LiveSession:
    """A running meshcat server (bound to one address, 127.0.0.1 by default) showing a view.

    Attributes:
        visualizer: the ``meshcat.Visualizer`` (draw more into it if wanted).
        web_url: address to open in a browser.
        zmq_url: address of the server's command socket.
        server: the server process (stopped by :meth:`close`).
    """

    visualizer: meshcat.Visualizer
    web_url: str
    zmq_url: str
    server: subprocess.Popen | None = None

    def close(self) -> None:
        """Stop the server subprocess started for this session."""
        if self.server is not None:
            _stop(self.server)


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
    host: str = "127.0.0.1",
    progress: Callable[[int, int], None] | None = None,
) -> LiveSession:
    """Start a meshcat server on ``host`` and draw the same view as :func:`static_html`.

    The server (a subprocess) listens on ``host`` only, the loopback interface by
    default; open ``session.web_url`` in a local browser and call ``session.close()``
    when done. It is also stopped when Python exits, and killed with this process
    (see the module doc). Other arguments are those of :func:`static_html`.

    Raises:
        VisualizationError: ``host`` is not an IPv4 address, or the server fails to start.
    """
    qs, arrow_list = check_inputs(model, configurations, arrows, arrow_scale, ghost_opacity)
    proc, zmq_url, web_url = _start_server(_check_host(host))
    banner = io.StringIO()
    try:
        with contextlib.redirect_stdout(banner):  # meshcat prints the URL; we log it
            vis = meshcat.Visualizer(zmq_url=zmq_url)
    except BaseException:
        _stop(proc)
        raise
    vis.window.server_proc = proc  # where meshcat's own launcher keeps it
    session = LiveSession(vis, web_url, zmq_url, proc)
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
            progress=progress,
        )
    except BaseException:
        session.close()
        raise
    return session
