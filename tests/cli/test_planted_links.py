"""A link planted inside a calibration directory is never written through.

A received calibration directory whose report.md (or report.html, validation.json)
is a symbolic link to one of the user's files: `pincal report` and `pincal validate
--out` refuse it, and the user's file keeps its bytes.
"""

from __future__ import annotations

import os

import pytest
from click.testing import CliRunner

from pincal.cli import main


@pytest.fixture(scope="module")
def calibration(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("planted")
    run = CliRunner().invoke
    assert run(main, ["simulate", "wedge3", "--random", "24", "--out", str(tmp / "m.csv")]
               ).exit_code == 0  # fmt: skip
    r = run(main, ["calibrate", "wedge3", "--data", str(tmp / "m.csv"), "--out", str(tmp / "cal")])
    assert r.exit_code == 0, r.output
    return tmp


@pytest.mark.parametrize("name", ["report.md", "report.html", "report.json"])
def test_report_refuses_a_planted_link(calibration, tmp_path, name):
    victim = tmp_path / "bashrc"
    victim.write_text("export KEEP=1\n")
    link = calibration / "cal" / name
    link.unlink(missing_ok=True)
    os.symlink(victim, link)
    try:
        r = CliRunner().invoke(main, ["report", str(calibration / "cal")])
        assert r.exit_code != 0 and "symbolic link inside the calibration directory" in r.output
        assert victim.read_text() == "export KEEP=1\n"
    finally:
        link.unlink()


def test_validate_out_refuses_a_planted_link(calibration, tmp_path):
    victim = tmp_path / "profile"
    victim.write_text("keep\n")
    link = calibration / "cal" / "validation.json"
    os.symlink(victim, link)
    try:
        r = CliRunner().invoke(main, ["validate", str(calibration / "cal"), "--data",
                                      str(calibration / "m.csv"), "--out", str(link)])  # fmt: skip
        assert r.exit_code != 0 and "symbolic link inside the calibration directory" in r.output
        assert victim.read_text() == "keep\n"
    finally:
        link.unlink()


@pytest.mark.parametrize("command", ["report", "validate"])
def test_a_planted_directory_link_is_not_written_through(calibration, tmp_path, command):
    """A link to a directory inside the calibration directory (``cal/sub -> ~``) is a
    link there too: an output under it is refused, the files it points to keep their bytes."""
    victim = tmp_path / "home"
    victim.mkdir()
    (victim / "report.md").write_text("keep\n")
    (victim / "v.json").write_text("keep\n")
    link = calibration / "cal" / "sub"
    os.symlink(victim, link)
    args = {"report": ["report", str(calibration / "cal"), "--out", str(link)],
            "validate": ["validate", str(calibration / "cal"), "--data",
                         str(calibration / "m.csv"), "--out", str(link / "v.json")]}  # fmt: skip
    try:
        r = CliRunner().invoke(main, args[command])
        said = " ".join(r.output.split())
        assert r.exit_code != 0 and "OutputPathError" in said, r.output
        assert f"passes through {link}, a symbolic link inside the calibration directory" in said
        assert sorted(p.name for p in victim.iterdir()) == ["report.md", "v.json"]
        assert {p.read_text() for p in victim.iterdir()} == {"keep\n"}
    finally:
        link.unlink()


def test_a_planted_lock_link_is_not_opened(calibration, tmp_path):
    """The writer's lock beside the directory (``.cal.pincal-lock``) planted as a dangling
    link: opening it with O_CREAT created the file it points to; now refused, nothing
    created, the calibration unchanged."""
    target = tmp_path / "created"
    lock = calibration / ".cal.pincal-lock"
    os.symlink(target, lock)
    before = {p.name: p.read_bytes() for p in (calibration / "cal").iterdir()}
    try:
        r = CliRunner().invoke(main, ["calibrate", "wedge3", "--data", str(calibration / "m.csv"),
                                      "--out", str(calibration / "cal")])  # fmt: skip
        said = " ".join(r.output.split())
        assert r.exit_code != 0 and "CalibrationDirectoryError" in said, r.output
        assert "is a symbolic link" in said and "remove it" in said
        assert not target.exists()
        assert {p.name: p.read_bytes() for p in (calibration / "cal").iterdir()} == before
    finally:
        lock.unlink()
