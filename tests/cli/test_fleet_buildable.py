"""`pincal fleet simulate` draws only errors a built machine can have (a 3-PRS head in
MJCF: the translations inside its emulated ball joint stay 0, as `pincal simulate`
leaves them)."""

from __future__ import annotations

import json

from click.testing import CliRunner

from pincal.cli import main
from pincal.model import degenerate_translations, load_mechanism
from tests.open_world.prs3_head import write_prs3_head


def test_fleet_truth_has_no_error_inside_an_emulated_joint(tmp_path):
    model = write_prs3_head(tmp_path)
    res = CliRunner().invoke(main, ["fleet", "simulate", str(model), "--units", "3", "--poses",
                                    "10", "--out", str(tmp_path / "fl")])  # fmt: skip
    assert res.exit_code == 0, res.output
    truth = json.loads((tmp_path / "fl" / "truth.json").read_text())
    split = set(degenerate_translations(load_mechanism(model)))
    assert split  # the case has them
    for unit in truth["units"]:
        values = dict(zip(truth["names"], unit["values"], strict=True))
        assert all(values[n] == 0.0 for n in split if n in values)
        assert sum(v != 0.0 for v in values.values()) > len(values) / 2
