"""`pincal info` prints the structure: closure ranks, joints, mobility, measured frame, notes."""

from __future__ import annotations

from pathlib import Path

import pytest
from click.testing import CliRunner

from pincal.cli import main

MACHINES = Path(__file__).parent / "machines"


@pytest.mark.slow
def test_info_prints_closure_ranks_joints_measured_frame_and_notes():
    res = CliRunner().invoke(main, ["info", str(MACHINES / "prs3"), "--preset", "full"])
    assert res.exit_code == 0, res.output
    out = res.output
    assert "closures: 3 (rank 9 of 9 rows at home)" in out
    assert "leg1_end ↔ anchor1  [3D]  rank 3/3" in out
    assert "actuated: slide1, slide2, slide3" in out
    assert "passive: platform_float, knee1, knee2, knee3" in out
    assert "mobility: 3" in out
    assert "measured frame: platform [x y z rx ry rz] (chosen automatically)" in out
    assert "other candidates:" in out
    assert "note: joint 'slide1' has a zero-width URDF <limit>" in out


def test_info_lists_free_passive_joints():
    res = CliRunner().invoke(main, ["info", str(MACHINES / "fivebar"), "--preset", "full"])
    assert res.exit_code == 0, res.output
    assert "free passive (not held by the actuators, do not move the measured frame): pin_l" in (
        res.output
    )
    assert "note: joint 'mot_l' has a zero-width URDF <limit>" in res.output
