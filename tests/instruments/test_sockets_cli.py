"""`pincal simulate --instrument socket` → `pincal calibrate --data … [--data …]`."""

from __future__ import annotations

import json
import re

import pytest
from click.testing import CliRunner

from pincal.cli import main


@pytest.fixture(scope="module")
def socket_files(tmp_path_factory):
    """Two socket files of one ur5 (same errors, other poses) in mm, and a pose file."""
    d = tmp_path_factory.mktemp("sockets")
    run = CliRunner()
    for name, seed in (("s1.csv", "1"), ("s2.csv", "2")):
        res = run.invoke(main, ["simulate", "ur5", "--random", "40", "--errors", "seed:2",
                                "--error-size", "1,10", "--noise", "0.005,0.01", "--seed", seed,
                                "--instrument", "socket", "--length-unit", "mm",
                                "--out", str(d / name)])  # fmt: skip
        assert res.exit_code == 0, res.output
    res = run.invoke(main, ["simulate", "ur5", "--random", "10", "--out", str(d / "p.csv")])
    assert res.exit_code == 0, res.output
    return d


def test_simulated_socket_file_calibrates(socket_files, tmp_path):
    truth = json.loads((socket_files / "s1.truth.json").read_text())
    assert sorted(truth["instrument"]) == [f"plate.{s}_{a}" for s in "AB" for a in "xyz"]
    assert "# distance: A, B, 50.0, 0.005" in (socket_files / "s1.csv").read_text()
    res = CliRunner().invoke(main, ["calibrate", "ur5", "--data", str(socket_files / "s1.csv"),
                                    "--out", str(tmp_path / "cal"), "--json"])  # fmt: skip
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout)
    assert 0.5 < doc["reduced_chi2"] < 2.0
    assert sorted(doc["instruments"]) == sorted(truth["instrument"])
    assert (tmp_path / "cal" / "calibrated.urdf").exists()
    report = (tmp_path / "cal" / "report.txt").read_text()
    found = re.search(r"distances between them \[mm\]: plate.A–plate.B ([\d.]+)", report)
    assert found and abs(float(found.group(1)) - 50.0) < 0.02


def test_without_the_known_distance_calibrate_refuses_in_words(socket_files, tmp_path):
    text = (socket_files / "s1.csv").read_text()
    nod = tmp_path / "nod.csv"
    nod.write_text("".join(line for line in text.splitlines(keepends=True)
                           if not line.startswith("# distance")))  # fmt: skip
    run = CliRunner()
    res = run.invoke(main, ["calibrate", "ur5", "--data", str(nod), "--out", str(tmp_path / "c")])
    assert res.exit_code != 0
    assert "nothing measured fixes the length scale: add the plate's known distance" in res.output
    assert not (tmp_path / "c").exists()
    res = run.invoke(main, ["calibrate", "ur5", "--data", str(nod), "--out", str(tmp_path / "c"),
                            "--force"])  # fmt: skip
    assert "warning: nothing measured fixes the length scale" in res.output
    assert (tmp_path / "c" / "identification.json").exists()
    doc = json.loads((tmp_path / "c" / "identification.json").read_text())
    assert any("length scale" in w for w in doc["warnings"])


def test_two_socket_files_share_the_plate(socket_files, tmp_path):
    res = CliRunner().invoke(main, ["calibrate", "ur5", "--data", str(socket_files / "s1.csv"),
                                    "--data", str(socket_files / "s2.csv"),
                                    "--out", str(tmp_path / "cal"), "--json"])  # fmt: skip
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout)
    centres = [k for k in doc["instruments"] if k.startswith("plate.")]
    assert len(centres) == 6  # one plate, two files
    assert doc["poses"] == 80


def test_a_pose_file_beside_a_socket_file_is_refused(socket_files, tmp_path):
    res = CliRunner().invoke(main, ["calibrate", "ur5", "--data", str(socket_files / "s1.csv"),
                                    "--data", str(socket_files / "p.csv"),
                                    "--out", str(tmp_path / "cal")])  # fmt: skip
    assert res.exit_code != 0
    assert "all are instrument files" in res.output


def test_simulate_socket_needs_random_poses(tmp_path):
    poses = tmp_path / "p.csv"
    poses.write_text("x\n")
    res = CliRunner().invoke(main, ["simulate", "ur5", "--poses", str(poses), "--instrument",
                                    "socket", "--out", str(tmp_path / "s.csv")])  # fmt: skip
    assert res.exit_code != 0
    assert "--instrument socket seats the ball itself: give --random N" in res.output
