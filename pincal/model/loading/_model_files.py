"""Where model files are: bundled models, model specs to paths, sidecar files."""

from __future__ import annotations

import difflib
import os
from pathlib import Path
from typing import Any

from pincal._yaml import load_yaml
from pincal.errors import ModelFileError, UnknownNameError, clip
from pincal.model.loading._robots import example_robot_names, example_robot_urdf

__all__ = ["MODELS_DIR", "bundled_models", "read_sidecar", "resolve_model_path"]

#: the bundled models (pincal/models links to the checkout's top-level models/; the wheel
#: ships them as package data)
MODELS_DIR = Path(__file__).resolve().parents[2] / "models"  # pincal/models


def read_sidecar(path: Path) -> dict[str, Any]:
    """Parse a sidecar YAML file safely (see :func:`pincal._yaml.load_yaml`).

    No code execution, a size cap, bounded alias expansion, duplicate keys refused.

    Raises:
        ModelFileError: unreadable, not UTF-8, not YAML, a duplicate key, not a mapping.
        InputLimitError: too large, an alias bomb or nesting too deep.
    """
    data = load_yaml(path, "sidecar", ModelFileError)
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise ModelFileError(
            f"sidecar {clip(str(path), 300)} must be a mapping of keys (closed_loop, name_mot, "
            f"...), got a {type(data).__name__}"
        )
    return data


def bundled_models() -> list[str]:
    """Names of the models shipped in ``models/``."""
    if not MODELS_DIR.is_dir():
        return []
    return sorted(p.name for p in MODELS_DIR.iterdir() if (p / f"{p.name}.urdf").is_file())


def resolve_model_path(spec: str | Path, by_name: bool = False) -> tuple[Path, Path | None]:
    """Find the URDF (and sidecar, if any) for a model spec.

    The spec is a model directory, a URDF path, a bundled model name or an
    example-robot-data robot name (e.g. ``ur10``). With ``by_name`` it is a name only
    (a local path of that name is not looked at).
    """
    path = Path(spec)
    if by_name and (MODELS_DIR / str(spec)).is_dir():
        return resolve_model_path(MODELS_DIR / str(spec))
    if by_name:
        urdf = _named_urdf(str(spec))
    elif path.is_dir():
        urdf = path / f"{path.name}.urdf"
        if not urdf.is_file():
            candidates = sorted(path.glob("*.urdf"))
            if len(candidates) != 1:
                raise ModelFileError(f"model directory {str(path)!r} must hold {path.name}.urdf")
            urdf = candidates[0]
    elif path.suffix.lower() == ".urdf":
        urdf = path
        if not urdf.exists():  # a FIFO or device is refused by the bounded reader
            raise ModelFileError(f"URDF file {str(path)!r} does not exist")
    elif (MODELS_DIR / str(spec)).is_dir():
        return resolve_model_path(MODELS_DIR / str(spec))
    elif path.exists() or (os.sep in str(spec) and str(spec) not in example_robot_names()):
        if not path.exists():
            what = "does not exist"
        elif not path.is_file():
            what = "is not a regular file"
        else:
            what = "is neither a model directory nor a .urdf or MJCF .xml file"
        raise ModelFileError(
            f"model {clip(str(spec))} {what}; give a model directory, a .urdf or an MJCF "
            ".xml file, or a model name (pincal --help lists them)"
        )
    else:
        urdf = _named_urdf(str(spec))
    sidecar = urdf.with_suffix(".yaml")
    return urdf, sidecar if sidecar.is_file() else None


def _named_urdf(name: str) -> Path:
    """The URDF of an example-robot-data robot name (UnknownNameError lists the names)."""
    robots = example_robot_names()
    if name not in robots:
        close = difflib.get_close_matches(name, robots, n=3)
        raise UnknownNameError(
            "model",
            name,
            bundled_models() + [f"{n} (example-robot-data)" for n in close],
            f" or one of {len(robots)} example-robot-data robots (e.g. ur10, panda)",
        )
    return example_robot_urdf(name)
