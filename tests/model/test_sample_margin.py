"""Random poses keep off the workspace edge (issue 36, item 5).

Before, random draws reached the actuator limits and the edge of the reachable set:
on the 2-RSU ankle with 0/0 limits, a draw at 0.06 of home's closure singular value
(motors −0.62, −1.40 rad) closed on the nominal model but not, from home, on the same
machine with a 2e-4 geometric error ("stopped at 97 % of the path"), so simulating it
failed.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from click.testing import CliRunner

import pincal
from pincal.cli import main
from pincal.errors import PincalError
from pincal.model import (
    MIN_SIGMA_RATIO,
    SAMPLE_MARGIN,
    WORKSPACE_POSE_KEYS,
    Mechanism,
    draw_actuators,
    load_mechanism,
    sample_actuators,
    sample_pose,
)
from pincal.model import _pose_screen as pose_screen
from pincal.model._pose_screen import passive_sigma, screen
from pincal.sensitivity import parameters
from tests.open_world.first_machines import SPM_RANGE, spherical_3rrr
from tests.open_world.machines import ankle_2rsu, write_machine


@pytest.fixture(scope="module")
def ankle():
    return Mechanism(*ankle_2rsu(zero_limits=True))


def _failing(mech: Mechanism, rows: np.ndarray, seeds: range) -> list[tuple[int, int]]:
    """(seed, row) pairs a machine with a normal 2e-4 error on the base set cannot close."""
    params = parameters(mech, "base")
    bad = []
    for seed in seeds:
        actual = params.apply(mech, np.random.default_rng(seed).normal(0, 2e-4, len(params)))
        for j, row in enumerate(rows):
            try:
                actual.configuration(row)
            except PincalError:
                bad.append((seed, j))
    return bad


def test_actuator_draws_keep_the_margin(tmp_path):
    mech = load_mechanism(write_machine(tmp_path, "spm", *spherical_3rrr()))
    rows = sample_actuators(mech, 300, np.random.default_rng(0))
    lo, hi = SPM_RANGE
    inner = (lo + SAMPLE_MARGIN * (hi - lo), hi - SAMPLE_MARGIN * (hi - lo))
    assert SAMPLE_MARGIN == 0.05
    assert rows.min() >= inner[0] and rows.max() <= inner[1]
    # and still spread over the inner range (the margin, not a collapse)
    assert rows.min() < inner[0] + 0.05 and rows.max() > inner[1] - 0.05


def test_pose_draws_keep_the_margin():
    stewart = pincal.load_mechanism("stewart_6ups")
    lim = stewart.workspace.pose
    assert lim
    home = stewart.frame_placement(stewart.q_home)
    rng = np.random.default_rng(1)
    for _ in range(200):
        T = sample_pose(stewart, rng)
        rot = pin.log3(home.rotation.T @ T.rotation)
        values = dict(zip(WORKSPACE_POSE_KEYS, (*T.translation, *rot), strict=True))
        for key, (lo, hi) in lim.items():
            gap = SAMPLE_MARGIN * (hi - lo) - 1e-12
            assert lo + gap <= values[key] <= hi - gap, key


def test_kept_draws_are_well_conditioned_and_close_on_a_perturbed_machine(ankle):
    rows, drawn = draw_actuators(ankle, 30, np.random.default_rng(11))
    floor = MIN_SIGMA_RATIO * passive_sigma(ankle, ankle.q_home)
    assert all(passive_sigma(ankle, ankle.configuration(r)) >= floor for r in rows)
    assert drawn.near_edge > 0  # the seed draws edge poses: they were rejected
    assert _failing(ankle, rows, range(8)) == []


def test_without_the_screen_the_same_draws_fail(ankle, monkeypatch):
    """The check above can fail: with the margin alone, the same seed keeps edge draws
    that the perturbed machines do not reach."""
    monkeypatch.setattr(pose_screen, "MIN_SIGMA_RATIO", 0.0)
    rows, drawn = draw_actuators(ankle, 30, np.random.default_rng(11))
    assert drawn.near_edge == 0
    assert _failing(ankle, rows, range(8)) != []


def test_screen_counts_the_edge_row(ankle):
    edge = np.array([[-0.617131, -1.395864]])  # the row that failed, 0.06 of home's
    inner = ankle.actuators_of(ankle.q_home)[None] + 0.1
    kept, unreached, near_edge = screen(ankle, np.vstack([edge, inner]))
    assert kept.tolist() == [False, True] and (unreached, near_edge) == (0, 1)


def test_cli_says_how_many_draws_were_rejected(tmp_path):
    model = write_machine(tmp_path, "ankle", *ankle_2rsu(zero_limits=True))
    runner = CliRunner()
    res = runner.invoke(main, ["simulate", str(model), "--random", "30", "--seed", "11",
                               "--params", "base", "--error-size", "0.2,2",
                               "--out", str(tmp_path / "m.csv")])  # fmt: skip
    assert res.exit_code == 0, res.output
    assert "random draws rejected:" in res.output and "near the workspace edge" in res.output
    res = runner.invoke(main, ["poses", str(model), "--count", "20", "--candidates",
                               "random:100", "--out", str(tmp_path / "p.csv")])  # fmt: skip
    assert res.exit_code == 0, res.output
    assert "near the workspace edge (closure σ_min < 0.2 × home's)" in res.output
