"""`select-model` with its default list on a machine that cannot take every term (a 3-PRS
head in MJCF: no link masses, prismatic actuators): the terms that do not apply are left
out and said, not a failure of the whole ranking; asked for by name, they still fail."""

from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from pincal.cli import main
from tests.open_world.prs3_head import write_prs3_head


@pytest.mark.slow
def test_default_models_leave_out_what_the_machine_cannot_take(tmp_path):
    model = write_prs3_head(tmp_path)
    data = tmp_path / "m.csv"
    res = CliRunner().invoke(main, ["simulate", str(model), "--random", "60", "--out", str(data)])
    assert res.exit_code == 0, res.output
    res = CliRunner().invoke(main, ["select-model", str(model), "--data", str(data), "--cv", "2",
                                    "--params", "base", "--json"])  # fmt: skip
    assert res.exit_code == 0, res.output
    assert "left out geometric+compliance: " in res.stderr and "no link masses" in res.stderr
    assert "left out geometric+harmonics: " in res.stderr and "prismatic" in res.stderr
    ranked = [s["model"] for s in json.loads(res.stdout)["candidates"]]
    assert sorted(ranked) == ["geometric", "geometric+gain"]
    res = CliRunner().invoke(main, ["select-model", str(model), "--data", str(data), "--cv", "2",
                                    "--models", "geometric,geometric+compliance"])  # fmt: skip
    assert res.exit_code == 1 and "no link masses" in res.output
