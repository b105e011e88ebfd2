"""`pincal calibrate` refuses silently wrong calibrations; --force writes and says so."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pinocchio as pin
import pytest
from click.testing import CliRunner

import pincal
from pincal.cli import main
from pincal.io import write_measurements
from pincal.model import sample_actuators

NOISE = pincal.NoiseModel(0.01, 0.02)


@pytest.fixture(scope="module")
def campaign(stewart, stewart42):
    rng = np.random.default_rng(21)
    actual = stewart42.apply(stewart, rng.normal(0.0, 3e-4, len(stewart42)))
    meas = pincal.simulate_measurements(actual, sample_actuators(stewart, 40, rng), NOISE, rng)
    return actual, meas


def _file(tmp_path, meas, name="m.csv", unit="mm"):
    path = tmp_path / name
    write_measurements(path, meas, length_unit=unit)
    return path


def _calibrate(path, out, *extra):
    args = ["calibrate", "stewart_6ups", "--data", str(path), "--out", str(out)]
    return CliRunner().invoke(main, [*args, *extra])


def _relabel(path, old, new):
    text = path.read_text().replace(f"# length_unit: {old}\n", f"# length_unit: {new}\n")
    path.write_text(text)
    return path


def test_clean_data_pass(tmp_path, campaign):
    res = _calibrate(_file(tmp_path, campaign[1]), tmp_path / "cal")
    assert res.exit_code == 0, res.output
    assert "quality gate: passed" in (tmp_path / "cal" / "report.txt").read_text()
    manifest = json.loads((tmp_path / "cal" / "calibration.json").read_text())
    assert manifest["quality"]["passed"] is True


@pytest.mark.parametrize(
    ("written", "declared", "scale", "named"),
    [
        ("mm", "m", 1.0, "mm declared as m"),
        ("m", "mm", 1.0, "m declared as mm"),
        ("mm", "mm", 0.1, "cm declared as mm"),
    ],
)
def test_unit_mistakes_exit_nonzero_and_write_nothing(
    tmp_path, campaign, written, declared, scale, named
):
    meas = dataclasses.replace(campaign[1], positions=campaign[1].positions * scale)
    path = _relabel(_file(tmp_path, meas, unit=written), written, declared)
    res = _calibrate(path, tmp_path / "cal")
    assert res.exit_code == 1
    assert "QualityGateError" in res.stderr and "Likely cause: units" in res.stderr
    assert named in res.stderr and "--force" in res.stderr
    assert "Traceback" not in res.output and len(res.stderr.strip().splitlines()[-1]) > 0
    assert not (tmp_path / "cal").exists()


def test_force_writes_and_the_report_says_so(tmp_path, campaign):
    path = _file(tmp_path, campaign[1])
    tight = ("--max-change", "0.001,0.00001")  # clean data, but the bound refuses them
    res = _calibrate(path, tmp_path / "cal", *tight, "--force")
    assert res.exit_code == 0, res.output
    assert "--force: writing despite the quality gate" in res.stderr
    quality = json.loads((tmp_path / "cal" / "calibration.json").read_text())["quality"]
    assert quality["passed"] is False and quality["overridden"] is True
    assert "moved beyond 0.001 mm" in quality["reason"]
    ident = json.loads((tmp_path / "cal" / "identification.json").read_text())
    assert ident["quality"]["overridden"] is True
    assert "OVERRIDDEN with --force" in (tmp_path / "cal" / "report.txt").read_text()
    res = CliRunner().invoke(main, ["report", str(tmp_path / "cal")])
    assert res.exit_code == 0, res.output
    md = (tmp_path / "cal" / "report.md").read_text()
    assert "## Quality gate" in md and "overridden with --force" in md
    report = json.loads((tmp_path / "cal" / "report.json").read_text())
    assert report["quality"]["overridden"] is True


@pytest.mark.slow
def test_force_past_a_unit_mistake_records_the_cause(tmp_path, campaign):
    path = _relabel(_file(tmp_path, campaign[1]), "mm", "m")
    res = _calibrate(path, tmp_path / "cal", "--force")
    assert res.exit_code == 0, res.output
    quality = json.loads((tmp_path / "cal" / "calibration.json").read_text())["quality"]
    assert quality["overridden"] is True and quality["cause"] == "units"
    assert "mm declared as m" in quality["reason"]


@pytest.mark.slow
def test_outliers_refused_then_huber_passes(tmp_path, campaign):
    meas = campaign[1]
    pos = meas.positions.copy()
    pos[[4, 22], 0] += 5e-3  # 5 % gross outliers
    path = _file(tmp_path, dataclasses.replace(meas, positions=pos))
    res = _calibrate(path, tmp_path / "cal")
    assert res.exit_code == 1 and "Likely cause: outliers" in res.stderr
    assert "--loss huber" in res.stderr and not (tmp_path / "cal").exists()
    res = _calibrate(path, tmp_path / "cal", "--method", "lm", "--loss", "huber")
    assert res.exit_code == 0, res.output
    assert "2 of 40 poses are outliers" in res.stderr and "poses 4, 22" in res.stderr
    text = (tmp_path / "cal" / "report.txt").read_text()
    assert "outlier poses" in text and "[4, 22]" in text


def test_duplicate_rows_warn(tmp_path, campaign):
    meas = campaign[1]
    doubled = dataclasses.replace(
        meas,
        q_act=np.repeat(meas.q_act, 2, axis=0),
        positions=np.repeat(meas.positions, 2, axis=0),
        rotations=np.repeat(meas.rotations, 2, axis=0),
    )
    res = _calibrate(_file(tmp_path, doubled), tmp_path / "cal")
    assert res.exit_code == 0, res.output
    assert "40 of 80 rows repeat an earlier row exactly" in res.stderr
    assert "repeat an earlier row" in (tmp_path / "cal" / "report.txt").read_text()


@pytest.mark.slow
def test_near_singular_pose_refused(tmp_path, stewart, campaign):
    actual, meas = campaign
    home = stewart.frame_placement(stewart.q_home)
    rot = pin.rpy.rpyToMatrix(0.0, 0.0, np.radians(89.8))
    row = actual.inverse(pin.SE3(rot @ home.rotation, home.translation), check_limits=False)
    rng = np.random.default_rng(5)
    bad = pincal.simulate_measurements(actual, np.vstack([meas.q_act, row]), NOISE, rng)
    res = _calibrate(_file(tmp_path, bad), tmp_path / "cal")
    assert res.exit_code == 1 and "Likely cause: singular pose" in res.stderr
    assert not (tmp_path / "cal").exists()


def test_max_change_option(tmp_path, campaign):
    path = _file(tmp_path, campaign[1])
    res = _calibrate(path, tmp_path / "cal", "--max-change", "0.001,0.00001")
    assert res.exit_code == 1 and "moved beyond 0.001 mm" in res.stderr
    res = _calibrate(path, tmp_path / "cal", "--max-change", "x")
    assert res.exit_code == 2 and "length_mm,angle_rad" in res.output


def _campaign_file(tmp_path, campaign):
    path = _relabel(_file(tmp_path, campaign[1]), "mm", "m")
    camp = tmp_path / "c.yaml"
    camp.write_text(
        f"model: stewart_6ups\nmeasurements: {{source: file, file: {path}}}\n"
        "validation: {source: none}\nreport: false\n"
    )
    return camp


def test_run_stops_at_a_refused_calibration(tmp_path, campaign):
    camp = _campaign_file(tmp_path, campaign)
    res = CliRunner().invoke(main, ["run", str(camp), "--out", str(tmp_path / "out")])
    assert res.exit_code == 1 and "step 'calibrate' failed" in res.stderr
    assert "Likely cause: units" in res.stderr and not (tmp_path / "out").exists()


@pytest.mark.slow
def test_run_force_passes_it_on(tmp_path, campaign):
    camp = _campaign_file(tmp_path, campaign)
    res = CliRunner().invoke(main, ["run", str(camp), "--out", str(tmp_path / "out"), "--force"])
    assert res.exit_code == 0, res.output
    manifest = json.loads((tmp_path / "out" / "calibration.json").read_text())
    assert manifest["quality"]["overridden"] is True
