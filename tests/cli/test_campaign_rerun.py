"""A campaign re-runs into its own out (issue 38, item 8).

The second run found the first's validation.json (which `pincal run` wrote) and refused
to replace the directory ("pincal did not write it"). A validation.json pincal's
validate wrote is now replaced with the calibration it validated; any other file of
that name is still a user's file, refused and named.
"""

from __future__ import annotations

import json

from click.testing import CliRunner

from pincal.cli import main

CAMPAIGN = """\
model: wedge3
preset: patent
out: cal
measurements: {source: simulated, poses: 12, errors_seed: 3, seed: 1}
validation: {source: simulated, poses: 6, seed: 2}
report: false
"""


def test_a_campaign_reruns_into_its_own_out(tmp_path):
    (tmp_path / "c.yaml").write_text(CAMPAIGN)
    for _ in range(2):
        res = CliRunner().invoke(main, ["run", str(tmp_path / "c.yaml")])
        assert res.exit_code == 0, res.output
    doc = json.loads((tmp_path / "cal" / "validation.json").read_text())
    assert "after" in doc
    # the README's `validate cal/ --data held_out.csv --out cal/validation.json`, then
    # calibrate again into cal/: replaced too
    (tmp_path / "cal" / "validation.json").write_text('{"my": "notes"}\n')
    res = CliRunner().invoke(main, ["run", str(tmp_path / "c.yaml")])
    assert res.exit_code == 1 and "validation.json" in res.output, res.output
    assert (tmp_path / "cal" / "validation.json").read_text() == '{"my": "notes"}\n'
