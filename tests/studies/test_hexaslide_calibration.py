"""Seed-001 study core claims (small instances of scripts/studies/hexaslide_calibration.py)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml

from pincal.compensation import compensate
from pincal.machines import (
    leg_geometry,
    legs_from_table,
    pus54_values,
)
from pincal.model import load_mechanism, parameters
from scripts.studies.seed001 import experiment_replica, paper_pose, simulation_check

PAPER = yaml.safe_load(
    (Path(__file__).resolve().parents[2] / "scripts" / "data" / "seed001.yaml").read_text()
)


@pytest.fixture(scope="module")
def hexa():
    mech = load_mechanism("hexaslide_6pus")
    return mech, parameters(mech, "pus54")


def closed_form_ik(legs, T: pin.SE3) -> np.ndarray:
    """The paper's IK, written independently: smaller root of |A − b − q u| = L."""
    out = []
    for leg in legs:
        d = T.rotation @ leg.a + T.translation - leg.b
        du = d @ leg.u
        out.append(du - np.sqrt(du**2 - d @ d + leg.L**2))
    return np.array(out)


def test_table_conversion_is_exact(hexa):
    mech, params = hexa
    legs = legs_from_table(PAPER["identified"])
    actual = params.apply(mech, pus54_values(mech, params, legs))
    for got, want in zip(leg_geometry(actual), legs, strict=True):
        assert np.allclose(got.as_row(), want.as_row(), atol=1e-14)
    T = paper_pose(PAPER["experiment_poses"][1])
    assert np.allclose(actual.inverse(T), closed_form_ik(legs, T), atol=1e-10)


def test_noise_free_simulation_check_recovers_paper_errors(hexa):
    mech, params = hexa
    sc = simulation_check(mech, params, PAPER, np.random.default_rng(1), n_candidates=30)
    assert sc.rank == 54
    assert sc.n_paper_poses == 5 and sc.n_paper_poses + sc.n_extra_poses >= 9
    assert sc.max_value_error <= 1e-9
    for name, assumed, _, _, ours, diff in sc.rows:
        assert ours == pytest.approx(assumed, abs=1e-6), name  # rows in mm and rad
        assert diff < 1e-6  # ≤ 1e-9 m


def test_compensation_reaches_targets_on_the_calibrated_model(hexa):
    mech, params = hexa
    legs = legs_from_table(PAPER["identified"])
    actual = params.apply(mech, pus54_values(mech, params, legs))
    targets = [paper_pose(p) for p in PAPER["experiment_poses"][:4]]
    far = pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.9]))
    comp = compensate(actual, [*targets, far])
    assert comp.unreachable == (4,)
    assert np.all(np.isnan(comp.q_act[4]))
    for T, q in zip(targets, comp.commands, strict=True):
        assert np.allclose(q, closed_form_ik(legs, T), atol=1e-10)


def test_replica_reaches_the_cramer_rao_floor(hexa):
    mech, params = hexa
    rr = experiment_replica(
        mech,
        params,
        PAPER,
        np.random.default_rng(5),
        n_extra=16,
        n_validation=12,
        n_trials=2,
        n_candidates=40,
    )
    assert rr.n_paper_poses == 8 and rr.n_extra_poses == 16
    assert not rr.unreachable
    t = rr.trials[0]
    assert t.result.identifiability.rank == 54
    # before: the identified table is ~20 mm / 0.04 rad off the nominal (paper Table 6)
    assert 0.010 < t.before.max_three_directions()[0] < 0.030
    # after: noise-limited, within 1.25 of the Cramér–Rao prediction (pooled)
    assert max(rr.efficiency) <= 1.25
    assert min(rr.efficiency) > 0.5
    assert t.after.max_three_directions()[0] < 0.046e-3  # below the paper's 0.046 mm
