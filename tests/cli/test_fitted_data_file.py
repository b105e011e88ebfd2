"""`validate --cv` finds the file a calibration was fitted on by its hash, from anywhere.

The manifest records the path as typed (relative to calibrate's directory) and the
absolute path; a different file of the same name in the current directory is not
cross-validated in its place, and a device named there is never read.
"""

from __future__ import annotations

import json
import sys

from click.testing import CliRunner

from pincal.cli import main


def test_cv_from_another_directory_uses_the_fitted_file(tmp_path, monkeypatch):
    run = CliRunner().invoke
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    monkeypatch.chdir(tmp_path / "a")
    assert run(main, ["simulate", "wedge3", "--random", "24", "--out", "m.csv"]).exit_code == 0
    assert run(main, ["calibrate", "wedge3", "--data", "m.csv", "--out", "cal"]).exit_code == 0
    monkeypatch.chdir(tmp_path / "b")  # another m.csv here: 20 other poses
    assert run(main, ["simulate", "wedge3", "--random", "20", "--seed", "3",
                      "--out", "m.csv"]).exit_code == 0  # fmt: skip
    out = run(main, ["validate", str(tmp_path / "a" / "cal"), "--cv", "3", "--json"])
    assert out.exit_code == 0, out.output
    assert json.loads(out.output)["cv"]["poses"] == 24
    (tmp_path / "a" / "m.csv").write_text("x\n")  # the fitted file changed
    out = run(main, ["validate", str(tmp_path / "a" / "cal"), "--cv", "3"])
    assert out.exit_code != 0 and "changed since" in out.output
    # moved away: only b's other m.csv is found; the message does not call it "changed"
    # alone (it may be another file of that name) and names the file as fitted
    (tmp_path / "a" / "m.csv").unlink()
    out = run(main, ["validate", str(tmp_path / "a" / "cal"), "--cv", "3"])
    said = " ".join(out.output.split())
    assert out.exit_code != 0 and "another file of that name" in said, said
    assert "(m.csv) is not found" in said
    (tmp_path / "b" / "m.csv").unlink()
    out = run(main, ["validate", str(tmp_path / "a" / "cal"), "--cv", "3"])
    assert out.exit_code != 0 and "is not found" in out.output


def test_a_project_moved_whole_finds_its_data_from_anywhere(tmp_path, monkeypatch):
    """The data file is recorded relative to the calibration directory too: a project
    (data/m.csv, cals/cal) moved whole is cross-validated from any directory; a
    different file put at that place is refused by its SHA-256, never cross-validated."""
    run = CliRunner().invoke
    (tmp_path / "p" / "data").mkdir(parents=True)
    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path / "p")
    assert run(main, ["simulate", "wedge3", "--random", "24", "--out", "data/m.csv"]).exit_code == 0
    r = run(main, ["calibrate", "wedge3", "--data", "data/m.csv", "--out", "cals/cal"])
    assert r.exit_code == 0, r.output
    entry = json.loads((tmp_path / "p" / "cals" / "cal" / "calibration.json").read_text())
    assert entry["data_files"][0]["relative_path"] == "../../data/m.csv"
    (tmp_path / "p").rename(tmp_path / "q")
    monkeypatch.chdir(tmp_path / "elsewhere")
    cal = str(tmp_path / "q" / "cals" / "cal")
    out = run(main, ["validate", cal, "--cv", "3", "--json"])
    assert out.exit_code == 0, out.output
    assert json.loads(out.output)["cv"]["poses"] == 24
    assert run(main, ["simulate", "wedge3", "--random", "20", "--seed", "3",
                      "--out", str(tmp_path / "q" / "data" / "m.csv")]).exit_code == 0  # fmt: skip
    out = run(main, ["validate", cal, "--cv", "3"])
    said = " ".join(out.output.split())
    assert out.exit_code != 0 and "CalibrationDirectoryError" in said, said
    assert "differs from its SHA-256" in said and "not found" in said


def test_a_data_file_swapped_after_its_check_is_not_cross_validated(tmp_path, monkeypatch):
    """The fitted file is hashed, then read by name: a file swapped in between (here
    right after the check) was parsed. The reader now compares the very bytes it
    parses with the recorded SHA-256 and refuses in one line."""
    from pincal.io import CalibrationDirectory

    monkeypatch.chdir(tmp_path)
    run = CliRunner().invoke
    assert run(main, ["simulate", "wedge3", "--random", "24", "--out", "m.csv"]).exit_code == 0
    assert run(main, ["calibrate", "wedge3", "--data", "m.csv", "--out", "cal"]).exit_code == 0
    assert run(main, ["simulate", "wedge3", "--random", "20", "--seed", "3",
                      "--out", "other.csv"]).exit_code == 0  # fmt: skip
    checked = CalibrationDirectory.data_file

    def swapped_after_check(self, index=0):
        path = checked(self, index)
        if sys._getframe(1).f_code.co_name == "reading_data_file":  # the check before a read
            (tmp_path / "other.csv").replace(path)
        return path

    monkeypatch.setattr(CalibrationDirectory, "data_file", swapped_after_check)
    out = run(main, ["validate", "cal", "--cv", "3"])
    said = " ".join(out.output.split())
    assert out.exit_code == 1 and "CalibrationDirectoryError" in said, said
    assert not (tmp_path / "other.csv").exists()  # the swap happened
    assert "changed after its SHA-256 was checked" in said and "20 poses" not in said
