"""Every public function, class and method has a docstring, in private modules too.

ruff's pydocstyle rules treat a ``_module.py`` as private and skip every name in it,
yet nearly all of pincal lives in such modules and reaches users through a stage's
``__init__`` (and the API reference). This check walks every module: each public name
defined there (no leading underscore) — function, class, and a class's own methods and
properties — has a docstring, its own or the one it inherits from the method it
overrides (``inspect.getdoc``), the way the API reference shows it.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil

import pincal

_MEMBER_KINDS = (staticmethod, classmethod, property)


def _modules() -> list[str]:
    names = ["pincal"]
    for info in pkgutil.walk_packages(pincal.__path__, "pincal."):
        if ".models" not in info.name and not info.name.endswith("__main__"):
            names.append(info.name)
    return names


def _undocumented(module_name: str) -> list[str]:
    module = importlib.import_module(module_name)
    missing = []
    for name, obj in vars(module).items():
        if name.startswith("_") or getattr(obj, "__module__", None) != module_name:
            continue
        if not (inspect.isfunction(obj) or inspect.isclass(obj)):
            continue
        if not inspect.getdoc(obj):
            missing.append(name)
        if not inspect.isclass(obj):
            continue
        for attr, raw in vars(obj).items():
            member = inspect.isfunction(raw) or isinstance(raw, _MEMBER_KINDS)
            if attr.startswith("_") or not member:
                continue
            if not inspect.getdoc(getattr(obj, attr, raw)) and not inspect.getdoc(raw):
                missing.append(f"{name}.{attr}")
    return [f"{module_name}.{m}" for m in missing]


def test_every_public_name_has_a_docstring() -> None:
    missing = [m for mod in _modules() for m in _undocumented(mod)]
    assert not missing, f"{len(missing)} public names without a docstring:\n" + "\n".join(missing)


def test_the_check_sees_a_name_without_a_docstring(tmp_path, monkeypatch) -> None:
    """The walk reaches private modules and methods (a mutation of the check fails here)."""
    pkg = tmp_path / "pincal_probe"
    pkg.mkdir()
    (pkg / "__init__.py").write_text('"""Probe."""\n')
    (pkg / "_private.py").write_text(
        '"""Probe module."""\n\n'
        "def bare(x):\n    return x\n\n"
        'class Kind:\n    """A kind."""\n\n    def step(self):\n        return 1\n\n'
        '    @property\n    def size(self):\n        """Documented."""\n        return 2\n'
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    assert _undocumented("pincal_probe._private") == [
        "pincal_probe._private.bare",
        "pincal_probe._private.Kind.step",
    ]
