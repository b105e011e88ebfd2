"""scripts/studies/pose_coverage.py run as a program: the same lines on every backend."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from tests.studies.scripts import ROOT


def _lines(*where: str) -> list[dict]:
    out = subprocess.run(
        [sys.executable, str(ROOT / "scripts/studies/pose_coverage.py"), "--seeds", "0:3", *where],
        check=True, capture_output=True, text=True, env={**os.environ, "PYTHONPATH": str(ROOT)},
    ).stdout  # fmt: skip
    return [{k: v for k, v in json.loads(ln).items() if k != "s"} for ln in out.splitlines()]


@pytest.mark.slow  # three draws, three times, one of them on a 2-worker Dask cluster
def test_draws_are_the_same_on_local_processes_and_on_dask():
    pytest.importorskip("distributed")
    serial = _lines("--jobs", "1")
    assert [r["seed"] for r in serial] == [0, 1, 2]
    assert all(r["k"] == 42 and 0 < r["d2k"] < 5 for r in serial)  # Stewart, 10 random poses
    assert _lines("--jobs", "2") == serial
    assert _lines("--scheduler", "local:2") == serial
