"""Stage boundaries of the package, checked on its source (AST, nothing imported).

A stage is a subpackage of ``pincal/``. docs/design.md, section "Stages and the import
rule" (and the docstring of ``pincal/__init__.py``) fixes their order, lowest first:
executor, model → {machines, sensitivity} → measure → design → identification → {compensation,
validation} → io → {workflow, export} → report / viz → cli. The rules checked here
(issue 24), without exceptions:

* another stage is entered only through its ``__init__`` or its declared interface
  module ``kernels`` — never through a private ``_module``, never for a ``_name``;
* a stage imports only lower stages (at module level, lazily or under
  ``TYPE_CHECKING`` alike) and registers nothing into a lower stage at import time;
* outside the CLI, other stages are imported at module level, not inside functions;
* inside a stage too, a ``_name`` never crosses a module boundary: what another module
  uses is public in the module that defines it (the size of a module is a matter of its
  concept, not of a line count);
* one level down, the same rule as between stages: a room of a stage (a sub-package by
  concept, e.g. ``pincal/model/loops/``) is entered from outside it only through its
  ``__init__``, never through one of its private modules.
"""

from __future__ import annotations

import ast
import functools
import re
import sys
from collections.abc import Iterator
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "pincal"

#: docs/design.md, "Stages and the import rule", lowest first; a stage may import only
#: stages of lower rank.
#: ``machines`` (machine-specific closed forms) sits on the model alone. The modules at
#: the top of the package (``_files``, ``_yaml``, ...) and the BASE packages are below
#: every stage.
RANK = {
    "executor": 0,
    "model": 0,
    "machines": 1,
    "sensitivity": 1,
    "measure": 2,
    "design": 3,
    "identification": 4,
    "compensation": 5,
    "validation": 5,
    "io": 6,
    "workflow": 7,
    "export": 7,
    "report": 8,
    "viz": 8,
    "cli": 9,
}

#: Modules a stage offers to later stages besides its ``__init__`` (no underscore).
INTERFACES = {"kernels"}

#: Subpackages below every stage, like the top-level modules (they import no stage);
#: every other module enters one only through its ``__init__``.
BASE = {"errors"}


def _stage(path: Path) -> str | None:
    """The stage a file of ``pincal/`` belongs to (None for the top-level modules and
    the BASE packages)."""
    parts = path.relative_to(PACKAGE).parts
    return parts[0] if len(parts) > 1 and parts[0] not in BASE else None


def _base_entered(rel: str, module: str) -> str | None:
    """The BASE package ``module`` belongs to when the file ``rel`` is outside it."""
    parts = module.split(".")
    inside = Path(rel).parts[1] if len(Path(rel).parts) > 2 else None
    if parts[0] != "pincal" or len(parts) < 2 or parts[1] not in BASE or parts[1] == inside:
        return None
    return parts[1]


@functools.cache
def _parse(path: Path, rel: str, mtime_ns: int) -> ast.Module:
    """The file's tree, parsed once per version for all the checks (they only read it)."""
    return ast.parse(path.read_text(encoding="utf-8"), rel)


def _files() -> Iterator[tuple[str, str | None, ast.Module]]:
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(PACKAGE.parent).as_posix()
        yield rel, _stage(path), _parse(path, rel, path.stat().st_mtime_ns)


def _absolute(node: ast.ImportFrom, rel: str) -> str:
    """The absolute module of a ``from ... import``, relative imports resolved."""
    if node.level == 0:
        return node.module or ""
    package = Path(rel).with_suffix("").parts[: -node.level]
    return ".".join([*package, *([node.module] if node.module else [])])


def _imports(tree: ast.Module, rel: str) -> Iterator[tuple[int, str, list[str]]]:
    """Every import anywhere in the file: (line, module, imported names)."""
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            yield node.lineno, _absolute(node, rel), [a.name for a in node.names]
        elif isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name, []


def _cross_stage(stage: str | None, module: str) -> str | None:
    """The other stage ``module`` belongs to, or None (same stage, top level, not us)."""
    parts = module.split(".")
    if parts[0] != "pincal" or len(parts) < 2 or parts[1] not in RANK or parts[1] == stage:
        return None
    return parts[1]


def private_module_imports() -> list[str]:
    """Imports of another stage's (or a BASE package's) private module or of a ``_name``
    from another stage."""
    found = []
    for rel, stage, tree in _files():
        for line, module, names in _imports(tree, rel):
            if _cross_stage(stage, module) is None and _base_entered(rel, module) is None:
                continue
            inner = module.split(".")[2:]
            private = [p for p in inner if p.startswith("_")]
            if inner and inner[0] not in INTERFACES and not private:
                private = inner  # a public submodule that is not a declared interface
            hidden = [n for n in names if n.startswith("_")]
            if private or hidden:
                found.append(f"{rel}:{line}: {module} {hidden or ''}".rstrip())
    return found


def private_name_imports() -> list[str]:
    """Imports of a ``_name`` (not a dunder) from any other module of the package."""
    found = []
    for rel, _, tree in _files():
        for line, module, names in _imports(tree, rel):
            hidden = [n for n in names if n.startswith("_") and not n.startswith("__")]
            if module.split(".")[0] == "pincal" and hidden:
                found.append(f"{rel}:{line}: {module} {hidden}")
    return found


def room_imports() -> list[str]:
    """Imports of a room's private module (``pincal.STAGE.ROOM._module``) from outside
    that room."""
    found = []
    for rel, _, tree in _files():
        for line, module, _names in _imports(tree, rel):
            parts = module.split(".")
            if len(parts) < 4 or parts[0] != "pincal" or not parts[3].startswith("_"):
                continue
            room = PACKAGE.joinpath(*parts[1:3])
            inside = rel.startswith(f"pincal/{parts[1]}/{parts[2]}/")
            if (room / "__init__.py").is_file() and not inside:
                found.append(f"{rel}:{line}: {module}")
    return found


def order_violations() -> dict[tuple[str, str], list[int]]:
    """Imports of a stage that is not lower: (file, module) → lines."""
    found: dict[tuple[str, str], list[int]] = {}
    for rel, stage, tree in _files():
        own = -1 if stage is None else RANK.get(stage)
        if own is None or rel in ("pincal/__init__.py", "pincal/__main__.py"):
            continue  # the package's __init__ gathers every stage; __main__ runs the CLI
        for line, module, _ in _imports(tree, rel):
            other = _cross_stage(stage, module)
            if other is not None and RANK[other] >= own:
                found.setdefault((rel, ".".join(module.split(".")[:2])), []).append(line)
    return found


def lazy_imports() -> dict[tuple[str, str], list[int]]:
    """Imports of another stage inside a function body, outside the CLI."""
    found: dict[tuple[str, str], list[int]] = {}
    for rel, stage, tree in _files():
        if stage == "cli":
            continue
        for func in ast.walk(tree):
            if not isinstance(func, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            for node in ast.walk(func):
                if isinstance(node, (ast.Import, ast.ImportFrom)):
                    for line, module, _ in _imports(ast.Module([node], []), rel):
                        if _cross_stage(stage, module) is not None:
                            key = (rel, ".".join(module.split(".")[:2]))
                            found.setdefault(key, []).append(line)
    return found


def import_time_registrations() -> dict[tuple[str, str], int]:
    """Module-level calls of a ``register*`` function imported from another stage."""
    found = {}
    for rel, stage, tree in _files():
        foreign = {
            name
            for _, module, names in _imports(tree, rel)
            if _cross_stage(stage, module) is not None
            for name in names
        }
        for node in tree.body:
            if not (isinstance(node, ast.Expr) and isinstance(node.value, ast.Call)):
                continue
            func = node.value.func
            name = func.id if isinstance(func, ast.Name) else getattr(func, "attr", "")
            if name.startswith("register") and name in foreign:
                found[(rel, name)] = node.lineno
    return found


def test_no_private_module_or_name_crosses_a_stage():
    offenders = private_module_imports()
    assert not offenders, (
        "import another stage through its __init__ (or its declared `kernels` module), "
        "never a private module or name:\n" + "\n".join(offenders)
    )


def test_no_private_name_crosses_a_module():
    offenders = private_name_imports()
    assert not offenders, (
        "a name another module imports is public where it is defined (drop the leading "
        "underscore there):\n" + "\n".join(offenders)
    )


def test_rooms_are_entered_through_their_init():
    offenders = room_imports()
    assert not offenders, (
        "import a room of a stage through its __init__ (export the name there), never "
        "one of its private modules from outside it:\n" + "\n".join(offenders)
    )


def test_stages_import_only_lower_stages():
    """A lower stage never imports a higher one: not at module level, not inside a
    function, not under ``TYPE_CHECKING``."""
    found = order_violations()
    where = "docs/design.md, 'Stages and the import rule'"
    assert not found, f"imports of a stage that is not lower ({where}):\n" + "\n".join(
        f"{rel}:{lines[0]}: {module}" for (rel, module), lines in sorted(found.items())
    )


def test_library_imports_other_stages_at_module_level():
    """Outside the CLI (which imports lazily so that ``pincal --help`` stays fast)."""
    found = lazy_imports()
    assert not found, "imports of another stage inside a function (import at the top):\n" + (
        "\n".join(f"{rel}:{lines[0]}: {module}" for (rel, module), lines in sorted(found.items()))
    )


#: a command module of the CLI: parse → one workflow call → print (issue 40)
COMMAND_LINES = 120


def test_the_cli_computes_nothing():
    """The CLI imports no numpy / scipy (anywhere in a file, lazily or for typing: the
    computation is the workflow's) and a command module — one defining a click
    command — stays a page: parse the options, call the workflow, print."""
    numeric, long = [], []
    for rel, stage, tree in _files():
        if stage != "cli":
            continue
        numeric += [f"{rel}:{line}: {module}" for line, module, _ in _imports(tree, rel)
                    if module.split(".")[0] in ("numpy", "scipy")]  # fmt: skip
        text = (PACKAGE.parent / rel).read_text(encoding="utf-8")
        if ".command(" in text and text.count("\n") > COMMAND_LINES:
            long.append(f"{rel}: {text.count(chr(10))} lines")
    assert not numeric, "numpy/scipy in the CLI (move the work to pincal.workflow):\n" + (
        "\n".join(numeric)
    )
    assert not long, f"command modules over {COMMAND_LINES} lines:\n" + "\n".join(long)


def test_no_stage_registers_into_a_lower_one_at_import():
    found = import_time_registrations()
    assert not found, "import-time registrations into another stage:\n" + "\n".join(
        f"{rel}:{line}: {name}(...)" for (rel, name), line in sorted(found.items())
    )


def test_the_stage_order_is_the_documented_one():
    """RANK (checked above) is the order pincal/__init__'s docstring lists, and every
    subpackage has a rank."""
    stages = {p.parent.name for p in PACKAGE.glob("*/__init__.py")} - BASE
    assert stages == set(RANK), f"stages without a rank, or ranks of no stage: {stages ^ set(RANK)}"
    doc = ast.get_docstring(ast.parse((PACKAGE / "__init__.py").read_text(encoding="utf-8")))
    assert doc is not None
    listed = [m for m in re.findall(r":mod:`pincal\.(\w+)`", doc) if m in RANK]
    first = sorted(set(listed), key=listed.index)
    ranks = [RANK[m] for m in first]
    assert set(first) == set(RANK) and ranks == sorted(ranks), (
        f"pincal/__init__ lists the stages as {first}; RANK: {sorted(RANK, key=RANK.get)}"
    )


def test_interface_modules_export_only_what_later_stages_use():
    used: dict[str, set[str]] = {}
    for rel, stage, tree in _files():
        for _, module, names in _imports(tree, rel):
            parts = module.split(".")
            if _cross_stage(stage, module) and len(parts) == 3 and parts[2] in INTERFACES:
                used.setdefault(module, set()).update(names)
    interfaces = sorted(
        f"pincal.{p.parent.name}.{p.stem}"
        for name in INTERFACES
        for p in PACKAGE.glob(f"*/{name}.py")
    )
    assert interfaces, "no declared interface module found"
    for module in interfaces:
        path = PACKAGE / module.split(".")[1] / f"{module.split('.')[2]}.py"
        tree = ast.parse(path.read_text(encoding="utf-8"))
        exported = next(
            {ast.literal_eval(e) for e in node.value.elts}
            for node in tree.body
            if isinstance(node, ast.Assign)
            and any(isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets)
            and isinstance(node.value, ast.List)
        )
        assert exported == used.get(module, set()), (
            f"{module}.__all__ must be exactly what other stages import from it: "
            f"unused {sorted(exported - used.get(module, set()))}, "
            f"missing {sorted(used.get(module, set()) - exported)}"
        )


def test_the_checks_see_violations(tmp_path, monkeypatch):
    """The scanners flag a planted private import, upward import and registration."""
    stage = tmp_path / "pincal" / "model"
    stage.mkdir(parents=True)
    (stage / "_bad.py").write_text(
        "from pincal.sensitivity._jacobian import _plan\n"
        "from pincal.sensitivity.extra import x\n"
        "from pincal.identification import register_solver\n"
        "def f():\n"
        "    from pincal.cli import main\n"
        "register_solver('x', None)\n",
        encoding="utf-8",
    )
    base = tmp_path / "pincal" / "errors"
    base.mkdir()
    (base / "__init__.py").write_text("from pincal.errors._kinds import KindError\n")
    (base / "_kinds.py").write_text("from pincal.model import Mechanism\n", encoding="utf-8")
    (tmp_path / "pincal" / "_top.py").write_text(
        "from pincal.errors._kinds import KindError\n", encoding="utf-8"
    )
    monkeypatch.setattr(sys.modules[__name__], "PACKAGE", tmp_path / "pincal")
    assert private_module_imports() == [
        "pincal/_top.py:1: pincal.errors._kinds",
        "pincal/model/_bad.py:1: pincal.sensitivity._jacobian ['_plan']",
        "pincal/model/_bad.py:2: pincal.sensitivity.extra",
    ]
    (stage / "_other.py").write_text("from pincal.model._bad import _helper, f\n", encoding="utf-8")
    assert private_name_imports() == [
        "pincal/model/_bad.py:1: pincal.sensitivity._jacobian ['_plan']",
        "pincal/model/_other.py:1: pincal.model._bad ['_helper']",
    ]
    room = stage / "loops"
    room.mkdir()
    (room / "__init__.py").write_text("from pincal.model.loops._newton import f\n")
    (room / "_newton.py").write_text("f = 1\n", encoding="utf-8")
    (room / "_branch.py").write_text("from pincal.model.loops._newton import f\n")
    (stage / "_mechanism.py").write_text("from pincal.model.loops._newton import f\n")
    assert room_imports() == ["pincal/model/_mechanism.py:1: pincal.model.loops._newton"]
    assert set(order_violations()) == {
        ("pincal/errors/_kinds.py", "pincal.model"),
        ("pincal/model/_bad.py", "pincal.sensitivity"),
        ("pincal/model/_bad.py", "pincal.identification"),
        ("pincal/model/_bad.py", "pincal.cli"),
    }
    assert import_time_registrations() == {("pincal/model/_bad.py", "register_solver"): 6}
    assert lazy_imports() == {("pincal/model/_bad.py", "pincal.cli"): [5]}
