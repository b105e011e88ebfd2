"""pincal fleet: a unit calibrated in two sessions is compared for drift."""

from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.errors import FleetFileError
from pincal.io import read_fleet


def _ok(args):
    res = CliRunner().invoke(main, args, catch_exceptions=False)
    assert res.exit_code == 0, res.output
    return res.output


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    root = tmp_path_factory.mktemp("drift") / "sim"
    _ok(["fleet", "simulate", "wedge3", "--units", "6", "--seed", "5", "--poses", "100",
         "--recalibrated", "3", "--drifted", "1", "--shift", "30", "--out", str(root)])  # fmt: skip
    out = root.parent / "run"
    printed = _ok(["fleet", "run", str(root / "FLEET.yaml"), "--out", str(out)])
    return root, out, printed


def test_the_drifted_unit_is_named_and_the_others_are_not(run):
    root, out, printed = run
    truth = json.loads((root / "truth.json").read_text())
    moved = {r["id"] for r in truth["recalibrated"] if r["drift"]}
    assert len(truth["recalibrated"]) == 3 and len(moved) == 1
    doc = json.loads((out / "fleet.json").read_text())
    assert {d["id"] for d in doc["drift"]} == {r["id"] for r in truth["recalibrated"]}
    assert set(doc["summary"]["drifted_ids"]) == moved
    assert doc["summary"]["units"] == 9 and doc["summary"]["unit_ids"] == 6
    (drifted,) = (d for d in doc["drift"] if d["drifted"])
    # the parameter that moved most is one of the moved part's
    part = next(r["drift"] for r in truth["recalibrated"] if r["drift"])
    assert drifted["largest"][0]["name"] in part
    assert f"{drifted['id']}: drifted 2026-01-15 → 2026-07-15" in printed
    assert "9 of 9 sessions of 6 units calibrated" in printed


def test_each_session_has_its_directory_and_the_family_test_takes_the_latest(run):
    _, out, _ = run
    doc = json.loads((out / "fleet.json").read_text())
    for u in doc["units"]:
        assert (out / u["calibration"] / "calibration.json").is_file()
        if "session" in u:
            assert u["calibration"] == f"units/{u['session']}"
            earlier = u["session"].endswith("2026-01-15")
            assert (u["out_of_family"] is None) == earlier
    assert doc["test"]["dof"] is not None
    assert "Drift between sessions" in (out / "fleet.md").read_text()
    assert "Drift between sessions" in (out / "fleet.html").read_text()


def test_a_repeated_id_needs_a_distinct_date(tmp_path):
    (tmp_path / "a.csv").write_text("x\n")
    fleet = tmp_path / "FLEET.yaml"
    for units, why in (
        ("[{id: A, data: a.csv}, {id: A, data: a.csv}]", "got none"),
        ("[{id: A, data: a.csv, date: 2026-01-01}, {id: A, data: a.csv, date: 2026-01-01}]",
         "distinct date"),
        ("[{id: A, data: a.csv, date: '1/2/26'}, {id: A, data: a.csv, date: x}]", "1/2/26"),
    ):  # fmt: skip
        fleet.write_text(f"model: wedge3\nunits: {units}\n")
        with pytest.raises(FleetFileError, match="appears 2 times") as err:
            read_fleet(fleet)
        assert why in str(err.value)
    fleet.write_text(
        "model: wedge3\nunits: [{id: A, data: a.csv, date: 2026-01-01}, "
        "{id: A, data: a.csv, date: 2026-02-01}, {id: B, data: a.csv}]\n"
    )
    labels = [u.label for u in read_fleet(fleet).units]
    assert labels == ["A@2026-01-01", "A@2026-02-01", "B"]
