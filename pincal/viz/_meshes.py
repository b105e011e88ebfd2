"""Where a view may read mesh files from: inside the model's directory unless allowed more.

A view embeds the bytes of every mesh it draws in the HTML page, so a URDF naming
``/home/me/.ssh/id_rsa`` or ``../../secret.stl`` would copy a local file of the
viewer's machine into a page that may be shared. Before Pinocchio (which loads the
meshes itself) sees the URDF, every ``<mesh filename>`` is resolved here:

* ``package://pkg/rest`` against the URDF's directory and its parents (the first
  holding ``pkg/rest``), as ROS does; ``file://path``, absolute and relative paths
  (relative to the URDF's directory) as they are; other URL schemes (``http://``) are
  refused: views never fetch anything;
* the resolved file (symbolic links followed) must lie inside the model's directory,
  or inside the ``package://`` package that holds the URDF itself (example-robot-data
  keeps its meshes beside the ``urdf`` folder), unless the caller allows meshes from
  anywhere (``allow_mesh_outside=True``, :func:`allow_mesh_outside`, or
  ``pincal view --allow-mesh-outside``);
* the file must exist and be readable.

The URDF handed to Pinocchio then names each mesh by the resolved absolute path, so
Pinocchio reads exactly the files checked here.
"""

from __future__ import annotations

import contextlib
import contextvars
import os
import re
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from pincal.errors import VisualizationError, clip

__all__ = ["MeshRef", "allow_mesh_outside", "checked_urdf", "mesh_access_allowed"]

_ALLOW_OUTSIDE: contextvars.ContextVar[bool] = contextvars.ContextVar(
    "pincal_allow_mesh_outside", default=False
)
_SCHEME = re.compile(r"^([A-Za-z][A-Za-z0-9+.-]*)://")
#: how many directories (the URDF's and its parents) package:// searches
_PACKAGE_DEPTH = 8


@contextlib.contextmanager
def allow_mesh_outside(allow: bool = True) -> Iterator[None]:
    """Within the block, views may read meshes outside the model's directory.

    For :func:`pincal.viz.live`, which has no keyword for it; :func:`static_html`
    takes ``allow_mesh_outside=True`` directly.
    """
    token = _ALLOW_OUTSIDE.set(allow)
    try:
        yield
    finally:
        _ALLOW_OUTSIDE.reset(token)


def mesh_access_allowed() -> bool:
    """Whether meshes outside the model's directory are allowed in this context."""
    return _ALLOW_OUTSIDE.get()


@dataclass(frozen=True)
class MeshRef:
    """One ``<mesh>`` of a URDF: its link, the filename as written and the resolved file."""

    link: str
    filename: str
    path: Path


def _fail(link: str, filename: str, why: str) -> VisualizationError:
    return VisualizationError(f"link '{clip(link)}' mesh '{clip(filename, 200)}': {why}")


def _resolve(link: str, filename: str, base: Path | None) -> tuple[Path, Path | None]:
    """The file a mesh filename names, and the package directory it came from (if any)."""
    match = _SCHEME.match(filename)
    if match and match.group(1).lower() == "package":
        rest = filename[len(match.group(0)) :]
        package, _, inside = rest.partition("/")
        if base is None or not package:
            raise _fail(link, filename, "a package:// mesh needs the URDF file's directory")
        for folder in [base, *base.parents][:_PACKAGE_DEPTH]:
            if (folder / package / inside).exists():
                return folder / package / inside, folder / package
        raise _fail(
            link,
            filename,
            f"package '{clip(package)}' with this file is not found in the model's "
            f"directory {clip(str(base), 200)} or its parents",
        )
    if match and match.group(1).lower() == "file":
        return Path(filename[len(match.group(0)) :]), None
    if match:
        raise _fail(
            link,
            filename,
            f"{match.group(1)}:// is not read: views use only local mesh files (inside the "
            "model's directory, or package:// resolved into it)",
        )
    path = Path(filename)
    if not path.is_absolute():
        path = (base or Path.cwd()) / path
    return path, None


def _inside(path: Path, root: Path) -> bool:
    try:
        return path.is_relative_to(root)
    except (OSError, ValueError):
        return False


def mesh_references(urdf_xml: str, urdf_path: Path | None, allow_outside: bool) -> list[MeshRef]:
    """Resolve and check every ``<mesh filename>`` of the URDF (see the module notes).

    Args:
        urdf_xml: URDF text.
        urdf_path: the URDF file (None for URDF text without a file: then every mesh is
            outside, i.e. allowed only with ``allow_outside``).
        allow_outside: accept meshes anywhere on the machine.

    Returns:
        One :class:`MeshRef` per mesh, in document order.

    Raises:
        VisualizationError: a mesh is outside the allowed directories, uses a URL scheme
            other than package:// or file://, or is missing or unreadable (the message
            names the link and the path).
    """
    try:
        root = ET.fromstring(urdf_xml)
    except ET.ParseError as exc:
        raise VisualizationError(f"the URDF to draw is not well-formed XML: {exc}") from None
    base = urdf_path.resolve().parent if urdf_path is not None else None
    real_urdf = urdf_path.resolve() if urdf_path is not None else None
    refs: list[MeshRef] = []
    for link in root.findall("link"):
        name = link.get("name", "")
        for mesh in link.findall("./*/geometry/mesh"):
            filename = mesh.get("filename", "")
            path, package = _resolve(name, filename, base)
            real = path.resolve()
            roots = [] if base is None else [base]
            if package is not None and real_urdf is not None:
                pkg = package.resolve()
                if _inside(real_urdf, pkg):
                    roots.append(pkg)
            if not allow_outside and not any(_inside(real, r) for r in roots):
                where = (
                    f"outside the model's directory {clip(str(base), 200)}"
                    if base is not None
                    else "not inside a model directory (the URDF was given as text)"
                )
                raise _fail(
                    name,
                    filename,
                    f"resolves to {clip(str(real), 200)}, {where}; views read meshes only "
                    "from the model's directory (a view embeds them in the page): move the "
                    "mesh there, or allow it with pincal view --allow-mesh-outside "
                    "(library: allow_mesh_outside=True)",
                )
            if not real.is_file():
                raise _fail(name, filename, f"{clip(str(real), 200)} is not an existing file")
            if not os.access(real, os.R_OK):
                raise _fail(name, filename, f"{clip(str(real), 200)} is not readable")
            refs.append(MeshRef(name, filename, real))
    return refs


def checked_urdf(urdf_xml: str, urdf_path: Path | None, allow_outside: bool) -> str:
    """The URDF text with every mesh filename replaced by its checked absolute path.

    Raises:
        VisualizationError: see :func:`mesh_references`.
    """
    refs = mesh_references(urdf_xml, urdf_path, allow_outside)
    if not refs:
        return urdf_xml
    root = ET.fromstring(urdf_xml)
    meshes = [m for link in root.findall("link") for m in link.findall("./*/geometry/mesh")]
    for mesh, ref in zip(meshes, refs, strict=True):
        mesh.set("filename", str(ref.path))
    return ET.tostring(root, encoding="unicode")
