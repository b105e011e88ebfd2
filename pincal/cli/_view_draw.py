"""``pincal view``'s outputs through :mod:`pincal.viz`: the HTML page and the live session.

The live meshcat session lasts until Enter on stdin (or SIGTERM / SIGHUP, turned into
SystemExit so that the server is stopped on the way out).
"""

from __future__ import annotations

import contextlib
import signal
import sys
from collections.abc import Iterator
from pathlib import Path
from types import FrameType
from typing import TYPE_CHECKING, Any, NoReturn, TypedDict

import click

from pincal.cli._progress import counted

if TYPE_CHECKING:
    from pincal.model import Mechanism
    from pincal.viz import Arrow, LiveSession

__all__ = ["ViewOptions", "draw_view", "wait_live"]


class ViewOptions(TypedDict):
    """Keywords shared by :func:`pincal.viz.static_html` and :func:`pincal.viz.live`."""

    frame: str | None
    ghosts: bool
    animate: bool
    arrows: list[Arrow]
    arrow_scale: float | None
    up: str


def _urdf_for_viz(mech: Mechanism) -> str | Path:
    """What viz draws from: the URDF file, or the URDF text of a model from MJCF."""
    src = mech.source
    if src is not None and Path(src).suffix.lower() == ".urdf" and Path(src).is_file():
        return Path(src)
    return mech.urdf_xml


def draw_view(
    mech: Mechanism,
    configurations: Any,
    title: str,
    options: ViewOptions,
    html_path: Path | None,
    live: bool,
    host: str,
    allow_mesh_outside: bool,
) -> tuple[str | None, LiveSession | None]:
    """Write the HTML page to ``html_path`` (if given) and open the live session (if ``live``).

    Args:
        mech: the mechanism drawn.
        configurations: (m, nq) its configurations, one per pose.
        title: the page's title.
        options: what is drawn and how (:class:`ViewOptions`).
        html_path: the page to write, or None.
        live: open a live meshcat session listening on ``host``.
        host: the IPv4 address the live server listens on.
        allow_mesh_outside: read meshes outside the model's directory too.

    Returns:
        (the page written, or None; the live session, or None).
    """
    from pincal import viz

    source = _urdf_for_viz(mech)
    written = session = None
    with viz.allow_mesh_outside(allow_mesh_outside):  # meshes are read (and embedded) here
        if html_path is not None:
            with counted("scene", unit="pose") as step:
                page = viz.static_html(
                    mech.model, source, list(configurations), title=title, progress=step,
                    **options,
                )  # fmt: skip
            written = str(viz.write_html(html_path, page))
        if live:
            with counted("live scene", unit="pose") as step:
                session = viz.live(
                    mech.model, source, list(configurations), host=host, progress=step,
                    **options,
                )  # fmt: skip
    return written, session


def wait_live(session: LiveSession) -> None:
    """Say where the live viewer is, wait for Enter on stdin, then stop it."""
    click.echo(f"meshcat viewer at {session.web_url} — press Enter to stop", err=True)
    try:
        with _exit_on_signals():
            sys.stdin.readline()
    finally:
        session.close()


@contextlib.contextmanager
def _exit_on_signals() -> Iterator[None]:
    """Turn SIGTERM / SIGHUP into SystemExit, so ``finally`` stops the live server."""

    def leave(signum: int, _frame: FrameType | None) -> NoReturn:
        raise SystemExit(128 + signum)

    wanted = [signal.SIGTERM] + ([signal.SIGHUP] if hasattr(signal, "SIGHUP") else [])
    old = {s: signal.signal(s, leave) for s in wanted}
    try:
        yield
    finally:
        for s, handler in old.items():
            signal.signal(s, handler)
