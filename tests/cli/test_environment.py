"""The ``PINCAL_MAX_*`` variables are read once, at the command line, and passed down as
:class:`pincal.model.Limits`; the library itself reads no environment."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest
from click.testing import CliRunner

import pincal
from pincal._limits import DEFAULT_MAX_BYTES, Limits, active_limits
from pincal.cli import main
from pincal.cli._environment import limits_from_environment
from pincal.errors import InputLimitError

PACKAGE = Path(pincal.__file__).parent


def test_every_variable_sets_its_limit_and_the_rest_keep_the_defaults():
    assert limits_from_environment({}) == Limits()
    assert limits_from_environment({"PINCAL_MAX_DOF": "", "HOME": "/x"}) == Limits()
    got = limits_from_environment(
        {
            "PINCAL_MAX_FILE_MB": "0.5",
            "PINCAL_MAX_LINKS": "7",
            "PINCAL_MAX_DOF": "8",
            "PINCAL_MAX_TREE_DEPTH": "9",
            "PINCAL_MAX_PARAMETERS": "10",
        }
    )
    assert got == Limits(file_bytes=2**19, links=7, dof=8, depth=9, parameters=10)
    assert Limits().file_bytes == DEFAULT_MAX_BYTES


@pytest.mark.parametrize("name", ["PINCAL_MAX_LINKS", "PINCAL_MAX_TREE_DEPTH"])
@pytest.mark.parametrize("text", ["0", "-3", "2.5", "many"])
def test_malformed_counts_are_refused_naming_the_variable(name, text):
    with pytest.raises(InputLimitError, match=rf"{name}=.* must be a positive integer"):
        limits_from_environment({name: text})


def test_a_command_runs_under_the_environment_limits_and_they_end_with_it(monkeypatch):
    monkeypatch.setenv("PINCAL_MAX_LINKS", "3")
    res = CliRunner().invoke(main, ["info", "wedge3"])
    assert res.exit_code == 1, res.output
    assert "over the limit of 3" in res.output and "PINCAL_MAX_LINKS=" in res.output
    assert active_limits() == Limits()  # nothing leaks past the command
    monkeypatch.delenv("PINCAL_MAX_LINKS")
    assert CliRunner().invoke(main, ["info", "wedge3"]).exit_code == 0


def test_the_library_reads_no_environment():
    """Only the CLI's environment module touches os.environ / getenv."""
    readers = set()
    for path in PACKAGE.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            name = node.attr if isinstance(node, ast.Attribute) else getattr(node, "id", "")
            if name in ("environ", "getenv", "environb"):
                readers.add(path.relative_to(PACKAGE).as_posix())
    assert readers <= {"cli/_environment.py", "cli/common.py"}, readers


def test_parallel_workers_rebuild_under_the_limits_of_the_caller(stewart):
    """joblib workers start with default limits: the recipe carries the caller's."""
    from pincal.design._parallel import _rebuild, _recipe

    with Limits(links=3).applied():
        recipe = _recipe(stewart)
    with pytest.raises(InputLimitError, match="over the limit of 3"):
        _rebuild(recipe)
    assert _rebuild(_recipe(stewart)).name == stewart.name
