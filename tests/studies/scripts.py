"""Load a script of ``scripts/`` as a module, for the tests of the studies."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

ROOT = Path(__file__).resolve().parents[2]


def load_script(name: str, folder: str = "studies", module: str | None = None) -> ModuleType:
    """``scripts/<folder>/<name>.py`` imported as ``module`` (default ``name``).

    The module is registered in ``sys.modules`` first: dataclasses look their module up.
    """
    module = module or name
    spec = importlib.util.spec_from_file_location(module, ROOT / "scripts" / folder / f"{name}.py")
    assert spec is not None and spec.loader is not None, f"no script {folder}/{name}.py"
    loaded = importlib.util.module_from_spec(spec)
    sys.modules[module] = loaded
    spec.loader.exec_module(loaded)
    return loaded
