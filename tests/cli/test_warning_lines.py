"""Library warnings reach the terminal as pincal's own warning lines (issue 38, item 10).

The command line configured Python's logging with its default format, so a library
warning printed as ``WARNING:pincal.model.files._build:…`` beside ``pincal: warning: …``
lines; --debug keeps the logger names.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

MIMIC = """<robot name="mim">
  <link name="base"/><link name="a"/><link name="b"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="a"/>
    <origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="a"/><child link="b"/>
    <origin xyz="0.3 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/><mimic joint="j1"/></joint>
</robot>
"""


def _info(tmp_path, *pre: str) -> str:
    urdf = tmp_path / "mim.urdf"
    urdf.write_text(MIMIC)
    res = subprocess.run([sys.executable, "-m", "pincal.cli", *pre, "info", str(urdf)],
                         cwd=ROOT, capture_output=True, text=True, timeout=120)  # fmt: skip
    assert res.returncode == 0, res.stderr
    return res.stderr


def test_a_library_warning_is_a_pincal_warning_line(tmp_path):
    err = _info(tmp_path)
    lines = [ln for ln in err.splitlines() if "mimics 'j1'" in ln]
    assert lines and all(ln.startswith("pincal: warning: joint 'j2'") for ln in lines), err
    assert "WARNING:" not in err
    assert "WARNING:pincal.model.files._build:" in _info(tmp_path, "--debug")
