"""Every subcommand has --json and examples; the group help lists every bundled model;
`pincal view` draws a model loaded from MJCF."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.model import bundled_models

MJCF = Path(__file__).parents[1] / "model" / "mjcf"


@pytest.mark.parametrize("name", sorted(main.commands))
def test_every_subcommand_has_json_and_examples(name):
    res = CliRunner().invoke(main, [name, "--help"])
    assert res.exit_code == 0
    assert "--json" in res.output, name
    assert "Examples:" in res.output and f"pincal {name}" in res.output, name


def test_group_help_lists_every_bundled_model_and_validate():
    res = CliRunner().invoke(main, ["--help"])
    models = bundled_models()
    assert len(models) >= 5
    for m in models:
        assert m in res.output
    assert "validate" in res.output


def test_view_of_a_model_loaded_from_mjcf(tmp_path):
    out = tmp_path / "delta.html"
    res = CliRunner().invoke(
        main, ["view", str(MJCF / "delta.xml"), "--random", "2", "--html", str(out), "--json"]
    )
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout)["poses"] == 2
    assert out.stat().st_size > 10_000
