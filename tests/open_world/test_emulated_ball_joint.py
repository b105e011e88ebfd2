"""Machine style: a ball joint emulated by three revolutes with intersecting axes
(machines.rssr_emulated_ball). The translations between the coincident axes are
degenerate; the ``base`` preset leaves them out."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from pincal.errors import UnreachablePoseError
from pincal.model import Mechanism, load_mechanism
from pincal.sensitivity import BASE_RTOL, RANK_RTOL, base_set, numerical_rank
from tests.open_world import acceptance
from tests.open_world.machines import rssr_emulated_ball, write_machine


@pytest.fixture(scope="module")
def model(tmp_path_factory) -> Path:
    return write_machine(tmp_path_factory.mktemp("m"), "rssr3r", *rssr_emulated_ball())


@pytest.fixture(scope="module")
def mech(model):
    return load_mechanism(model)


def test_base_preset_leaves_out_translations_between_coincident_axes(mech):
    from pincal.model import degenerate_translations
    from pincal.sensitivity import parameters

    degenerate = {f"ball_{a}.t{d}" for a in "yz" for d in "xyz"}
    assert set(degenerate_translations(mech)) == degenerate
    assert degenerate.isdisjoint(parameters(mech, "base").names)
    assert degenerate <= set(parameters(mech, "full").names)


def test_round_trip(mech):
    acceptance.check_round_trip(mech)


def test_jacobian_matches_central_differences(mech):
    acceptance.check_jacobian(mech)


def test_noise_free_recovery_of_the_measured_quantity(mech):
    acceptance.check_recovery(mech, tol=None)


def test_noise_free_recovery(mech):
    acceptance.check_recovery(mech)


def test_simulate_calibrate_compensate(model, tmp_path):
    acceptance.check_cli(model, tmp_path)


# ------------------------------------------------------------------ causes of the old xfails
def _symmetric():
    """The same machine with home at the output dead point and a range around it (as the
    acceptance tests had it first)."""
    urdf, sidecar = rssr_emulated_ball()
    return Mechanism(
        urdf,
        dict(
            sidecar,
            home=dict(sidecar["home"], crank_mot=0.0),
            workspace={"joints": {"crank_mot": [-0.6, 0.6]}},
        ),
    )


def test_inverse_from_a_dead_point_says_so():
    """The old round-trip failure: not the idle spin, but a mirror-symmetric output whose
    dead point was home (crank a and −a give one rocker-tip position)."""
    mech = _symmetric()
    p, m = mech.forward([0.3]).translation, mech.forward([-0.3]).translation
    assert np.max(np.abs(p - m)) <= 1e-12
    with pytest.raises(
        UnreachablePoseError,
        match=r"dead point of the output.*crank_mot|"
        r"crank_mot.*dead point of the output",
    ):
        mech.inverse(mech.forward([0.3]))


def test_base_preset_leaves_out_weak_directions():
    """Around the dead point one direction has σ = 2.2e-8·σ1: above the rank rule, below
    BASE_RTOL; the base preset leaves it out and says why."""
    b = base_set(_symmetric())
    assert b.weak == 1 and RANK_RTOL < b.weakest <= BASE_RTOL
    assert "1 weakly identifiable direction(s) left out" in b.note()
    assert numerical_rank(b.analysis.singular_values, RANK_RTOL) == len(b.params) + 1


def test_forward_kinematics_keeps_home_branch_despite_the_idle_spin(mech):
    """The passive closure Jacobian is 3 × 4 (idle coupler spin): the branch is checked on
    the block without the idle column. A guess on the other rocker branch is corrected."""
    assert mech.home_branch == 0.0 and mech.idle_branch != 0.0
    q_act = np.array([0.7])
    q_home_branch = mech.configuration(q_act)
    qi = mech.model.idx_qs[mech.model.getJointId("rocker_pivot")]
    guess = q_home_branch.copy()
    guess[qi] = -2.5  # the Newton solve from here closes the loop on the other branch
    q = mech.configuration(q_act, q_guess=guess)
    assert abs(q[qi] - q_home_branch[qi]) <= 1e-9


def test_info_says_why_weak_directions_are_not_in_the_base_preset(tmp_path):
    urdf, sidecar = rssr_emulated_ball()
    sidecar = dict(
        sidecar,
        home=dict(sidecar["home"], crank_mot=0.0),
        workspace={"joints": {"crank_mot": [-0.6, 0.6]}},
    )
    model = write_machine(tmp_path, "rssr3r", urdf, sidecar)
    out = acceptance.invoke("info", model)
    assert "preset 'base': 13 parameters, all identifiable" in out
    assert "1 weakly identifiable direction(s) left out (singular value down to 2.2e-08" in out
    doc = json.loads(acceptance.invoke("info", model, "--json"))
    assert doc["base_preset"]["weak_directions_left_out"] == 1
