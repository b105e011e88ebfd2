"""Machines from published geometry (tests/open_world/paper_machines.py): the Agile Eye
(robot.urdf + robot.yaml, closures named by joints, orientation only), a 6-RSS Stewart
head in MJCF (freejoint, ``connect site1 site2``, keyframe) and Clavel's Delta with
IRB 360 dimensions (every ball end three revolutes).

Checked here: forward kinematics stays on home's assembly branch at far commands
(against a continuation in small steps written in this file), `pincal simulate` with
its default preset draws errors a built machine can have (issue 36: the over-constrained
wrist and the emulated balls made the simulated machine unbuildable), and `pincal poses`
reduces a preset to the same base set as `info` and `calibrate`. Exact-data recovery
runs in test_roster.py (the machines are in the roster)."""

from __future__ import annotations

import json
import logging
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.model import Mechanism, degenerate_translations, load_mechanism, sample_actuators
from pincal.sensitivity import base_parameters, parameters
from tests.open_world.continuation import continuation
from tests.open_world.machines import write_machine
from tests.open_world.paper_machines import clavel_delta, write_agile_eye, write_stewart

WRITERS = {
    "agile_eye": write_agile_eye,
    "stewart_6rss": write_stewart,
    "clavel_delta": lambda folder: write_machine(folder, "clavel_delta", *clavel_delta()),
}


@pytest.fixture(scope="module")
def models(tmp_path_factory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("paper")
    return {name: write(folder) for name, write in WRITERS.items()}


def _load(path: Path) -> Mechanism:
    logging.disable(logging.WARNING)
    try:
        return load_mechanism(path)
    finally:
        logging.disable(logging.NOTSET)


@pytest.mark.parametrize("name", list(WRITERS))
def test_loads_closed_at_home_with_its_mobility(models, name):
    mech = _load(models[name])
    assert mech.mobility == mech.n_actuated
    assert np.max(np.abs(mech.closure_residual(mech.q_home))) <= 1e-12


@pytest.mark.parametrize("name", list(WRITERS))
def test_forward_stays_on_homes_branch_at_far_commands(models, name):
    """The 6 of 40 random commands farthest from home: ``forward`` (a fresh call, its
    own start) = the pose the continuation from home reaches, ≤ 1e-9 m / rad."""
    mech = _load(models[name])
    rows = sample_actuators(mech, 40, np.random.default_rng(2))
    a0 = mech.actuators_of(mech.q_home)
    far = rows[np.argsort(-np.linalg.norm(rows - a0, axis=1))[:6]]
    for row in far:
        T = mech.forward(row)
        C = mech.frame_placement(continuation(mech, row))
        assert np.max(np.abs(T.translation - C.translation)) <= 1e-9, row
        assert np.max(np.abs(pin.log3(T.rotation.T @ C.rotation))) <= 1e-9, row


def _simulate(model: Path, out: Path) -> dict:
    res = CliRunner().invoke(main, ["simulate", str(model), "--random", "8", "--out", str(out)])
    assert res.exit_code == 0, res.output
    truth = json.loads(out.with_suffix(".truth.json").read_text())
    return {p["name"]: p["value"] for p in truth["parameters"]}


def test_default_simulation_of_an_overconstrained_wrist_assembles(models, tmp_path):
    """The Agile Eye's 6d closures are over-constrained (all axes through one point):
    55 of its 72 ``full`` parameters move an axis off the centre. Errors drawn on them
    gave an actual machine that cannot be assembled (ClosureError before the fix)."""
    truth = _simulate(models["agile_eye"], tmp_path / "m.csv")
    assert len(truth) == 72
    assert all(truth[f"seat2.t{d}"] == 0.0 for d in "xyz")  # breaks the closure
    assert truth["base1.offset"] != 0.0


def test_default_simulation_keeps_emulated_balls_whole(models, tmp_path):
    """A translation between the three revolutes of an emulated ball splits it (the
    mechanism gains freedoms: MobilityError before the fix); simulate leaves them 0."""
    mech = _load(models["clavel_delta"])
    truth = _simulate(models["clavel_delta"], tmp_path / "m.csv")
    split = degenerate_translations(mech)
    assert len(split) == 42 and all(truth[n] == 0.0 for n in split)
    assert sum(v != 0.0 for v in truth.values()) == len(truth) - 42


def test_poses_reduces_full_to_the_base_preset_info_offers(models):
    """One rank decision: the base set of ``full`` (what `poses` and `calibrate` use)
    is the ``base`` preset (57 parameters with split-joint translations before the fix,
    38 in `info`)."""
    mech = _load(models["clavel_delta"])
    reduced = base_parameters(mech, parameters(mech, "full"))
    assert reduced.names == parameters(mech, "base").names
    assert not set(reduced.names) & set(degenerate_translations(mech))


def test_reach_screen_imposes_the_components_a_planar_machine_controls(tmp_path):
    """The five-bar measures x y rz with 2 actuators: its reach screen now runs (its
    errors used to break the planar loop, so it never did) and imposes x y — all three
    were refused with MobilityError by compensate."""
    from pincal.workflow import controlled_components
    from tests.sensitivity.five_bar import FIVE_BAR_SIDECAR, FIVE_BAR_URDF

    mech = Mechanism(FIVE_BAR_URDF, FIVE_BAR_SIDECAR)
    assert tuple(mech.measured_components) == ("x", "y", "rz")
    assert controlled_components(mech) == ("x", "y")
    stewart = _load(write_stewart(tmp_path))
    assert controlled_components(stewart) == ("x", "y", "z", "rx", "ry", "rz")


def test_a_planar_machine_measured_in_six_components_imposes_its_three():
    """The 3-RPR measures all six components; its actuator Jacobian's z, rx, ry rows are
    closure rounding (~1e-15). Counted as rank by numpy's default tolerance, z was imposed,
    every candidate of `pincal poses` failed the reach screen and `poses` refused."""
    from pincal.workflow import controlled_components

    rpr3 = load_mechanism(Path(__file__).parents[1] / "model" / "machines" / "rpr3")
    assert len(rpr3.measured_components) == 6
    assert controlled_components(rpr3) == ("x", "y", "rz")
