"""``pincal calibrate --link LEFT,RIGHT``: one marker table, a marker on each arm of TALOS.

The chains from the left sole to both wrists share the leg and the torso; the table is
simulated with Pinocchio's model of TALOS as shipped (``reroot_sim``), and
``validate --cv`` replays the two-chain set-up the calibration recorded.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.measure import marker_mechanism
from pincal.model import sample_actuators
from tests.identification.reroot_sim import perturbed_model
from tests.identification.test_two_chains import LEFT, RIGHT, ROOT, SETUP, _table

LINKS = f"{LEFT},{RIGHT}"
COLUMNS = "xl,yl,zl;xr,yr,zr"


def _run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_one_link_per_marker_set(tmp_path):
    r = _run("calibrate", "talos", "--link", LINKS, "--root", ROOT, "--marker-columns",
             "xl,yl,zl", "--data", tmp_path / "t.csv", "--out", tmp_path / "cal")  # fmt: skip
    assert r.exit_code != 0 and "2 links for 1 marker column sets" in r.output


@pytest.mark.slow  # ~30 s: the prior chosen by nested CV over 22 joints
def test_two_arms_from_the_sole_calibrate_and_cross_validate(tmp_path):
    mech = marker_mechanism("talos", SETUP)
    q = sample_actuators(mech, 60, np.random.default_rng(3))
    _table(tmp_path / "t.csv", mech, perturbed_model("talos", 1e-3, 0), q, 1e-4, 4)
    r = _run("calibrate", "talos", "--link", LINKS, "--root", ROOT, "--marker-columns",
             COLUMNS, "--length-unit", "mm", "--data", tmp_path / "t.csv", "--out",
             tmp_path / "cal", "--json")  # fmt: skip
    assert r.exit_code == 0, r.output
    cal = json.loads((tmp_path / "cal" / "calibration.json").read_text())
    assert cal["markers"]["more_links"] == [RIGHT]
    r = _run("validate", tmp_path / "cal", "--cv", "5", "--seed", "1", "--json")
    assert r.exit_code == 0, r.output
    cv = json.loads(r.output.splitlines()[-1])["cv"]
    # 0.1 mm noise per coordinate (0.17 mm per point) on both markers
    assert cv["held_out_rms_mm"] < 0.3 and cv["baseline"]["held_out_rms_mm"] > 3.0


def _campaign(tmp_path, more_links: str) -> str:
    text = f"""model: talos
measurements: {{source: file, file: t.csv}}
validation: {{source: none}}
markers:
  link: {LEFT}
  columns: [xl, yl, zl]
  more_columns: [[xr, yr, zr]]
  more_links: {more_links}
  root: {ROOT}
"""
    (tmp_path / "c.yaml").write_text(text)
    (tmp_path / "t.csv").write_text("xl\n")  # (read when the campaign runs, not here)
    return str(tmp_path / "c.yaml")


def test_a_campaign_names_the_links_and_the_root(tmp_path):
    from pincal.cli._campaign import load_campaign
    from pincal.errors import CampaignError

    markers = load_campaign(_campaign(tmp_path, f"[{RIGHT}]")).markers
    assert markers is not None
    opts = markers.options()
    assert opts[opts.index("--link") + 1] == LINKS and opts[opts.index("--root") + 1] == ROOT
    with pytest.raises(CampaignError, match="one link per more_columns entry"):
        load_campaign(_campaign(tmp_path, f"[{RIGHT}, {LEFT}]"))
