"""`simulate` skips the poses the erroneous machine cannot reach and says which and why
(issue 36, item 5: the campaign used to abort at the first such pose)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from click.testing import CliRunner

from pincal.cli import main
from pincal.io import read_measurements
from pincal.model import load_mechanism, sample_actuators

PRS3 = Path(__file__).parents[1] / "model" / "machines" / "prs3"


def test_unreachable_poses_are_skipped_named_and_left_out(tmp_path):
    out = tmp_path / "m.csv"
    args = ["simulate", str(PRS3), "--random", "60", "--error-size", "5,50", "--out", str(out)]
    res = CliRunner().invoke(main, [*args, "--json"])
    assert res.exit_code == 0, res.output
    summary = json.loads(res.stdout.strip().splitlines()[-1])
    skipped = summary["skipped_rows"]
    assert skipped and summary["poses"] == 60 - len(skipped)  # 5 mm / 50 mrad: some lost
    assert f"skipped {len(skipped)} of 60 poses the actual machine cannot reach" in res.stderr
    assert "rows " + ", ".join(map(str, skipped[:3])) in res.stderr
    truth = json.loads(out.with_suffix(".truth.json").read_text())
    assert truth["skipped_rows"] == skipped
    # the file holds exactly the reached rows, in order
    mech = load_mechanism(PRS3)
    meas = read_measurements(out, mech)
    rows = sample_actuators(mech, 60, np.random.default_rng(1))  # --seed 1
    kept = np.setdiff1d(np.arange(60), np.array(skipped) - 1)
    np.testing.assert_allclose(meas.q_act, rows[kept], atol=1e-12)
