"""A calibration directory made with --lock / --frame / --sidecar can be copied and moved
(issue 38, item 7): its nominal model is its own model.yaml, not the first directory's.

Before, ``model_source`` held the absolute path of the first directory's model.yaml: a
copy read the original's file (and failed once the original was moved), a moved
directory failed to load its nominal model.
"""

from __future__ import annotations

import json
import shutil

import yaml
from click.testing import CliRunner

from pincal.cli import main


def _run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_a_locked_calibration_is_copied_and_moved(tmp_path):
    opts = ["--frame", "wrist_3_link", "--lock", "wrist_3_joint=0"]
    res = _run("simulate", "ur5", "--random", "30", *opts, "--out", tmp_path / "m.csv")
    assert res.exit_code == 0, res.output
    res = _run("calibrate", "ur5", *opts, "--params", "base", "--data", tmp_path / "m.csv",
               "--out", tmp_path / "cal")  # fmt: skip
    assert res.exit_code == 0, res.output
    shutil.copytree(tmp_path / "cal", tmp_path / "copy")
    (tmp_path / "cal").rename(tmp_path / "moved")
    for name in ("copy", "moved"):
        res = _run("validate", tmp_path / name, "--data", tmp_path / "m.csv")
        assert res.exit_code == 0, (name, res.output)
    # the copy reads its own model.yaml: a change there is seen (the record is hashed)
    record = yaml.safe_load((tmp_path / "copy" / "model.yaml").read_text())
    assert record["lock"] == {"wrist_3_joint": 0.0}
    (tmp_path / "copy" / "model.yaml").write_text(yaml.safe_dump({**record, "lock": {}}))
    res = _run("validate", tmp_path / "copy", "--data", tmp_path / "m.csv")
    assert res.exit_code == 1 and "model.yaml" in res.output, res.output


def test_a_project_moved_whole_loads_its_model_from_anywhere(tmp_path, monkeypatch):
    """A model kept in the project (mymodel/, calibrated with --frame) moves with it: the
    manifest names model.yaml relative to the directory and the model relative to it
    too; validate from another directory loads the moved model, checked by its SHA-256
    (an edited URDF is refused, not loaded)."""
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    project = tmp_path / "p"
    project.mkdir()
    shutil.copytree(root / "models" / "wedge3", project / "mymodel")
    monkeypatch.chdir(project)
    assert _run("simulate", "wedge3", "--random", "24", "--out", "m.csv").exit_code == 0
    res = _run("calibrate", "mymodel", "--frame", "bar_centre", "--data", "m.csv",
               "--out", "cals/cal")  # fmt: skip
    assert res.exit_code == 0, res.output
    manifest = json.loads((project / "cals" / "cal" / "calibration.json").read_text())
    assert manifest["model_source"] == "model.yaml"
    assert manifest["model_relative"] == "../../mymodel" and manifest["model_files"]
    project.rename(tmp_path / "moved")
    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path / "elsewhere")
    cal = tmp_path / "moved" / "cals" / "cal"
    res = _run("validate", cal, "--data", tmp_path / "moved" / "m.csv")
    assert res.exit_code == 0, res.output
    urdf = tmp_path / "moved" / "mymodel" / "wedge3.urdf"
    urdf.write_text(urdf.read_text().replace("<robot", "<!-- edited -->\n<robot", 1))
    res = _run("validate", cal, "--data", tmp_path / "moved" / "m.csv")
    said = " ".join(res.output.split())
    assert res.exit_code == 1 and "CalibrationDirectoryError" in said, said
    assert "cannot load the nominal model" in said
