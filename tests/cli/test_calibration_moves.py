"""A calibration directory made with --lock / --frame / --sidecar can be copied and moved
(issue 38, item 7): its nominal model is its own model.yaml, not the first directory's.

Before, ``model_source`` held the absolute path of the first directory's model.yaml: a
copy read the original's file (and failed once the original was moved), a moved
directory failed to load its nominal model.
"""

from __future__ import annotations

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
