"""Robots of the installed example-robot-data package, found by name (no network, no ROS)."""

from __future__ import annotations

import functools
import importlib.metadata
from pathlib import Path

from pincal.errors import ModelFileError, UnknownNameError

__all__ = ["example_robot_names", "example_robot_urdf"]

#: short names for robots whose URDF file stem differs from the usual name.
#: ``talos*``: the names example-robot-data's own loader gives those URDFs.
_ERD_ALIASES = {
    "ur10": "ur10_robot",
    "ur5": "ur5_robot",
    "talos": "talos_reduced",
    "talos_arm": "talos_left_arm",
    "talos_full": "talos_full_v2",
}
_ERD_MARKER = "share/example-robot-data/robots/"


@functools.cache
def _erd_index() -> tuple[dict[str, Path], list[str]]:
    """(all accepted names → path, the short names to show)."""
    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError as exc:
        raise ModelFileError(
            "the example-robot-data package is not installed (pip install example-robot-data)"
        ) from exc
    files = [f for f in (dist.files or ()) if _ERD_MARKER in str(f) and str(f).endswith(".urdf")]
    by_stem: dict[str, list[Path]] = {}
    stubs: list[str] = []
    for f in files:
        path = Path(str(dist.locate_file(f)))
        if _is_stub(path):  # e.g. ur3.urdf: a xacro leftover without links
            stubs.append(path.stem)
            continue
        by_stem.setdefault(path.stem, []).append(path)
    index: dict[str, Path] = {}
    shown: list[str] = []
    for stem, paths in by_stem.items():
        for path in paths:
            package = path.relative_to(_erd_robots_dir(path)).parts[0]
            qualified = f"{package.removesuffix('_description')}/{stem}"
            index[qualified] = path
            if len(paths) > 1:
                shown.append(qualified)
        if len(paths) == 1:
            index[stem] = paths[0]
            shown.append(stem)
    aliases = dict(_ERD_ALIASES) | {stub: f"{stub}_robot" for stub in stubs}
    for alias, stem in aliases.items():
        if alias not in index and stem in index:
            index[alias] = index[stem]
            shown.append(alias)
    return index, sorted(shown)


def _is_stub(path: Path) -> bool:
    """A URDF file without any <link> (a macro file left over by xacro)."""
    try:
        with path.open("rb") as fh:
            head = fh.read(1 << 16)
    except OSError:
        return False
    return b"<link" not in head


def _erd_robots_dir(path: Path) -> Path:
    for parent in path.parents:
        if parent.name == "robots" and parent.parent.name == "example-robot-data":
            return parent
    raise ModelFileError(f"{path} is not inside example-robot-data/robots")


def example_robot_names() -> list[str]:
    """Robot names for :func:`example_robot_urdf`, sorted.

    A name is the URDF file stem (``panda``, ``ur10_robot``), or
    ``<package>/<stem>`` (``anymal_b_simple/anymal``) when the stem is ambiguous,
    plus the aliases ``ur5``, ``ur10``, ``talos`` (``talos_reduced``), ``talos_arm``
    and ``talos_full`` (the names of example-robot-data's loader). The qualified form
    ``<package>/<stem>`` is accepted for every robot but only listed for ambiguous stems.
    """
    return _erd_index()[1]


def example_robot_urdf(name: str) -> Path:
    """Path of a URDF shipped by the installed example-robot-data package.

    Resolved from the installed distribution's file list (no network, no ROS).
    Natural measured frames: UR arms ``tool0`` (fixed joint
    ``wrist_3_link-tool0_fixed_joint`` on ``wrist_3_link``); Panda
    ``panda_hand_tcp`` or ``panda_hand`` (fixed joints on ``panda_link8``, itself
    fixed on ``panda_link7``; the two finger joints are prismatic).

    Raises:
        UnknownNameError: ``name`` is not a known robot (the message lists them).
        ModelFileError: example-robot-data is not installed or the file is missing.
    """
    index, shown = _erd_index()
    if name not in index:
        raise UnknownNameError("robot", name, shown)
    path = index[name]
    if not path.is_file():
        raise ModelFileError(f"example-robot-data lists {path} but the file does not exist")
    return path
