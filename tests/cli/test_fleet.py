"""pincal fleet: simulate, run serial and on 2 Dask workers, resume, a failing unit, drift."""

from __future__ import annotations

import importlib.util
import json
import shutil

import pytest
from click.testing import CliRunner
from scipy.stats import chi2

from pincal.cli import main
from pincal.errors import FleetFileError
from pincal.io import read_fleet


def _ok(args):
    res = CliRunner().invoke(main, args, catch_exceptions=False)
    assert res.exit_code == 0, res.output
    return res.output


@pytest.fixture(scope="module")
def fleet_dir(tmp_path_factory):
    root = tmp_path_factory.mktemp("fleet") / "sim"
    _ok(["fleet", "simulate", "wedge3", "--units", "8", "--seed", "3", "--poses", "100",
         "--shift", "30", "--out", str(root)])  # fmt: skip
    return root


@pytest.fixture(scope="module")
def serial(fleet_dir, tmp_path_factory):
    out = tmp_path_factory.mktemp("serial")
    _ok(["fleet", "run", str(fleet_dir / "FLEET.yaml"), "--out", str(out)])
    return out


def _units(out):
    return json.loads((out / "fleet.json").read_text())["units"]


def test_the_planted_unit_is_flagged_and_the_report_written(fleet_dir, serial):
    truth = json.loads((fleet_dir / "truth.json").read_text())
    planted = {p["id"] for p in truth["planted"]}
    assert len(planted) == 1 and len(truth["units"]) == 8
    units = _units(serial)
    assert [u["status"] for u in units] == ["calibrated"] * 8
    flagged = {u["id"] for u in units if u["out_of_family"]}
    assert flagged == planted
    for u in units:
        assert 0 <= u["p_value"] <= 1 and u["distance"] >= 0
        assert (serial / u["calibration"] / "calibration.json").is_file()
    doc = json.loads((serial / "fleet.json").read_text())
    # 8 units < CALIBRATE_BELOW: the limit is calibrated by fault-free fleets, never above α/M
    test = doc["test"]
    assert test["correction"] == "calibrated by fault-free fleets"
    assert 0 < test["per_unit_p_threshold"] <= 0.01 / 8
    assert test["distance_threshold"] == pytest.approx(
        chi2.isf(test["per_unit_p_threshold"], test["dof"]), rel=1e-9
    )
    for u in units:
        assert u["out_of_family"] == (u["p_value"] < test["per_unit_p_threshold"])
    assert (serial / "fleet_parameters.png").stat().st_size > 1000
    assert "out of family: 1" in (serial / "fleet.md").read_text()
    assert "<img" in (serial / "fleet.html").read_text()


def test_a_rerun_recomputes_nothing(fleet_dir, serial, monkeypatch):
    import pincal.cli._fleet_unit as unit

    calls = []
    real = unit.calibrate_unit
    monkeypatch.setattr(unit, "calibrate_unit", lambda item: calls.append(item) or real(item))
    before = {p: p.stat().st_mtime_ns for p in serial.glob("units/*/calibration.json")}
    out = _ok(["fleet", "run", str(fleet_dir / "FLEET.yaml"), "--out", str(serial)])
    assert calls == [] and "8 of 8 units calibrated" in out
    assert before == {p: p.stat().st_mtime_ns for p in serial.glob("units/*/calibration.json")}
    # without the per-unit results, complete calibration directories are read back
    shutil.rmtree(serial / ".fleet-results")
    out = _ok(["fleet", "run", str(fleet_dir / "FLEET.yaml"), "--out", str(serial)])
    assert len(calls) == 8 and "(8 read back)" in out
    assert before == {p: p.stat().st_mtime_ns for p in serial.glob("units/*/calibration.json")}


@pytest.mark.skipif(importlib.util.find_spec("distributed") is None, reason="no dask")
def test_two_dask_workers_give_the_serial_report(fleet_dir, serial, tmp_path):
    _ok(["fleet", "run", str(fleet_dir / "FLEET.yaml"), "--out", str(tmp_path),
         "--scheduler", "local:2"])  # fmt: skip
    keep = ("id", "status", "out_of_family", "distance", "p_value", "values")
    strip = [{k: u[k] for k in keep} for u in _units(serial)]
    assert strip == [{k: u[k] for k in keep} for u in _units(tmp_path)]


def test_a_failing_unit_is_reported_and_the_others_calibrated(fleet_dir, tmp_path):
    sim = tmp_path / "sim"
    shutil.copytree(fleet_dir, sim)
    (sim / "SN-0002" / "measurements.csv").write_text("not,a\nmeasurement,file\n")
    out = _ok(["fleet", "run", str(sim / "FLEET.yaml"), "--out", str(tmp_path / "rep"),
               "--jobs", "2"])  # fmt: skip
    units = _units(tmp_path / "rep")
    assert units[1]["status"] == "failed" and units[1]["out_of_family"] is None
    assert "SN-0002" in units[1]["reason"]
    assert [u["status"] for i, u in enumerate(units) if i != 1] == ["calibrated"] * 7
    assert "1 failed" in out


def test_a_unit_data_file_over_the_cap_is_refused_at_once(fleet_dir, tmp_path, monkeypatch):
    """A unit's data file is hashed as every input is read: a sparse file over the size
    cap (it was hashed whole: 98 s for 20 GB) is refused in one line before any unit runs."""
    sim = tmp_path / "sim"
    shutil.copytree(fleet_dir, sim)
    with open(sim / "SN-0002" / "measurements.csv", "wb") as fh:
        fh.truncate(50 << 20)
    monkeypatch.setenv("PINCAL_MAX_FILE_MB", "1")
    res = CliRunner().invoke(main, ["fleet", "run", str(sim / "FLEET.yaml"),
                                    "--out", str(tmp_path / "rep")])  # fmt: skip
    assert res.exit_code == 1, res.output
    line = res.output.strip().splitlines()[-1]
    assert line.startswith("pincal: error: InputLimitError: data file"), line
    assert "measurements.csv" in line and "PINCAL_MAX_FILE_MB" in line, line
    assert not (tmp_path / "rep" / "units").exists()


# --------------------------------------------------- a unit calibrated in two sessions


@pytest.fixture(scope="module")
def drift_run(tmp_path_factory):
    """wedge3, 6 units, 3 measured in a second session, 1 of them with a moved part."""
    root = tmp_path_factory.mktemp("drift") / "sim"
    _ok(["fleet", "simulate", "wedge3", "--units", "6", "--seed", "5", "--poses", "100",
         "--recalibrated", "3", "--drifted", "1", "--shift", "30", "--out", str(root)])  # fmt: skip
    out = root.parent / "run"
    printed = _ok(["fleet", "run", str(root / "FLEET.yaml"), "--out", str(out)])
    return root, out, printed


def test_the_drifted_unit_is_named_and_the_others_are_not(drift_run):
    root, out, printed = drift_run
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


def test_each_session_has_its_directory_and_the_family_test_takes_the_latest(drift_run):
    _, out, _ = drift_run
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
