"""``python -m pincal`` runs the command line (issue 36: a new user's `python -m pincal
info M` stopped at "No module named pincal.__main__")."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_python_dash_m_pincal_runs_the_cli():
    res = subprocess.run(
        [sys.executable, "-m", "pincal", "--help"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=False,
    )
    assert res.returncode == 0, res.stderr
    assert res.stdout.startswith("Usage: pincal ")
    assert "simulate" in res.stdout and "calibrate" in res.stdout
