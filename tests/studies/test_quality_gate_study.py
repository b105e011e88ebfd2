"""Smoke test of scripts/studies/quality_gate.py: one fit of a clean and a faulty cell."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from tests.studies.scripts import ROOT, load_script


def test_one_fit_per_cell_reports_rates(capsys):
    study = load_script("quality_gate", module="quality_gate_study")
    cells = "clean, Stewart, declared;1 % leg gain"
    assert study.main(["--fits", "1", "--poses", "40", "--cells", cells]) == 0
    out = capsys.readouterr().out
    rows = [ln for ln in out.splitlines() if ln.startswith("| ") and "/1 " in ln]
    clean = next(ln for ln in rows if ln.startswith("| clean, Stewart, declared"))
    faults = [ln for ln in rows if ln.startswith("| 1 % leg gain")]
    pooled = next(ln for ln in rows if ln.startswith("| all clean cells"))
    assert "0/1" in clean and "false alarms: —" in clean and "0/1" in pooled
    assert len(faults) == 2  # the fault with estimated and with declared noise
    assert all("1/1" in ln and "detected:" in ln and "model" in ln for ln in faults)
    assert len(rows) == 4  # only the cells asked for, and the pooled clean row


@pytest.mark.slow  # a 2-worker Dask cluster and 3 × 3 fits, the script run as a program
def test_the_table_is_the_same_on_local_processes_and_on_dask():
    pytest.importorskip("distributed")
    cells = "clean, Stewart, declared;one 5 mm outlier in 30, Stewart, estimated"
    tables = []
    for where in (["--jobs", "1"], ["--jobs", "2"], ["--scheduler", "local:2"]):
        out = subprocess.run(
            [sys.executable, str(ROOT / "scripts/studies/quality_gate.py"), "--fits", "3",
             "--poses", "40", "--cells", cells, *where],
            check=True, capture_output=True, text=True, env={**os.environ, "PYTHONPATH": str(ROOT)},
        ).stdout  # fmt: skip
        tables.append([ln for ln in out.splitlines() if ln.startswith("| ")])
    assert len(tables[0]) == 4 and "named exactly:   3/3" in tables[0][2]
    assert tables[1] == tables[0] and tables[2] == tables[0]
