"""Candidates from mechanisms, stated scalings, Cramér–Rao reports, pose selection, CLI."""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest
from click.testing import CliRunner

import pincal
from pincal.design import (
    DesignScaling,
    candidate_set,
    characteristic_length,
    cramer_rao,
    cramer_rao_from_jacobian,
    default_grid_ranges,
    dimensionless_rows,
    efficiency,
    grid_candidates,
    observability,
    orthogonal_candidates,
    parse_candidate_spec,
    random_candidates,
    select_poses,
    weight_rows,
)
from pincal.errors import (
    PincalError,
    UnidentifiableError,
    UnknownNameError,
)
from pincal.io import (
    read_commands,
    read_poses,
    write_pose_design,
)
from pincal.model import COMPONENTS


@pytest.fixture(scope="module")
def stewart():
    mech = pincal.load_mechanism("stewart_6ups")
    return mech, pincal.parameters(mech, "stewart42")


@pytest.fixture(scope="module")
def random_cands(stewart):
    mech, params = stewart
    return random_candidates(mech, params, 120, rng=3)


# ----------------------------------------------------------------------------- candidates


def test_grid_candidates_are_feasible_and_carry_their_jacobians(stewart):
    mech, params = stewart
    ranges = default_grid_ranges(mech)
    assert ranges.shape == (6, 2) and np.all(ranges[:, 0] < ranges[:, 1])
    lo, hi = np.asarray(mech.actuator_limits).T
    assert np.all(ranges[:, 0] >= lo) and np.all(ranges[:, 1] <= hi)
    calls = []
    c = grid_candidates(mech, params, 2, progress=lambda d, t: calls.append((d, t)))
    assert c.tried == 64 and calls[-1] == (64, 64)
    assert len(c) + sum(c.rejected.values()) == 64
    assert 0 < len(c) < 64  # extreme corners leave the pose workspace
    # every kept row: its grid values, FK pose = stored pose, inside the workspace box
    for q in c.q_act:
        for k in range(6):
            assert np.min(np.abs(q[k] - ranges[k])) < 1e-12
    home = mech.forward(mech.actuators_of(mech.q_home))
    for q, p, R in zip(c.q_act, c.positions, c.rotations, strict=True):
        T = mech.forward(q)
        np.testing.assert_allclose(T.translation, p, atol=1e-10)
        r = pin.log3(home.rotation.T @ R)
        for i, key in enumerate(("x", "y", "z")):
            lo_k, hi_k = mech.workspace.pose[key]
            assert lo_k - 1e-9 <= p[i] <= hi_k + 1e-9
        for i, key in enumerate(("rx", "ry", "rz")):
            lo_k, hi_k = mech.workspace.pose[key]
            assert lo_k - 1e-9 <= r[i] <= hi_k + 1e-9
    # Jacobian blocks equal the identification Jacobian of the same rows
    J = pincal.identification_jacobian(mech, params, c.q_act[:3])
    np.testing.assert_allclose(c.jacobians[:3].reshape(-1, len(params)), J, atol=1e-10)
    # without the workspace filter all 64 corners close (a 2-level grid is all corners)
    c_all = grid_candidates(mech, params, 2, in_workspace=False)
    assert len(c_all) == 64


def test_orthogonal_candidates_reach_the_array_poses(stewart):
    mech, params = stewart
    c = orthogonal_candidates(mech, params, 3)  # smallest Bose array with 6 factors: p = 5
    assert c.tried == 25 and len(c) == 25 and c.source == "oa:L25(5^6)"
    pose = mech.workspace.pose
    xs = np.unique(np.round(c.positions[:, 0], 9))
    np.testing.assert_allclose(xs, np.linspace(*pose["x"], 5), atol=1e-9)
    # strength 2 survives the mapping: every (x, y) level pair occurs exactly once
    pairs = {(round(a, 9), round(b, 9)) for a, b in c.positions[:, :2]}
    assert len(pairs) == 25


def test_random_candidates_and_specs(stewart, random_cands):
    mech, params = stewart
    assert len(random_cands) == 120 and random_cands.jacobians.shape == (120, 6, 42)
    assert parse_candidate_spec("grid:4") == ("grid", 4)
    assert parse_candidate_spec("oa") == ("oa", 5)
    with pytest.raises(PincalError, match="grid:LEVELS"):
        parse_candidate_spec("sobol:3")
    with pytest.raises(PincalError, match="not an integer"):
        parse_candidate_spec("random:x")
    sub = random_cands.subset([3, 1])
    np.testing.assert_array_equal(sub.q_act, random_cands.q_act[[3, 1]])
    assert len(candidate_set(mech, params, "random:4", rng=1)) == 4


# ----------------------------------------------------------------------------- scaling


def test_design_scaling_matches_the_primitive_scalings(random_cands):
    J = random_cands.jacobians[:10]
    comps = random_cands.components
    jzg = DesignScaling(rows="K", K=0.6).apply(J, comps)
    np.testing.assert_allclose(jzg.J, dimensionless_rows(J, 0.6).J)
    assert "K = 600 mm" in jzg.description
    white = DesignScaling(rows="noise", position_std=1e-5, orientation_std=2e-5).apply(J, comps)
    np.testing.assert_allclose(white.J, weight_rows(J, [1e-5] * 3 + [2e-5] * 3).J)
    # column norms over the whole candidate set become 1
    cn = DesignScaling(rows="none", columns="norm").apply(J, comps)
    np.testing.assert_allclose(np.linalg.norm(cn.J.reshape(-1, J.shape[2]), axis=0), 1.0)
    np.testing.assert_allclose(cn.params_to_physical(np.ones(42)), cn.col_scale)
    # the seed's unscaled Jz in mm units = SI rows with orientation × 1 mm = K of 1 mm,
    # up to one overall factor (all indices are then proportional, O2 equal)
    J_mm = J.copy()
    J_mm[:, 3:] *= 1e-3
    jz = DesignScaling(rows="K", K=1e-3).apply(J, comps).J
    assert observability(jz).O2 == pytest.approx(observability(J_mm).O2, rel=1e-9)
    with pytest.raises(UnknownNameError):
        DesignScaling(rows="mm")
    with pytest.raises(PincalError, match="positive length"):
        DesignScaling(rows="K")
    with pytest.raises(PincalError, match="orientation_std"):
        DesignScaling(rows="noise", position_std=1e-5).apply(J, comps)


def test_characteristic_length_balances_the_row_blocks():
    rng = np.random.default_rng(0)
    J = rng.standard_normal((50, 6, 5))
    J[:, 3:] /= 0.25  # rotation rows 4× larger
    K = characteristic_length(J, COMPONENTS)
    rms_p, rms_r = np.sqrt(np.mean(J[:, :3] ** 2)), np.sqrt(np.mean(J[:, 3:] ** 2))
    assert K == pytest.approx(rms_p / rms_r) and 0.2 < K < 0.3
    scaled = DesignScaling(rows="K", K=K).apply(J, COMPONENTS).J
    assert np.sqrt(np.mean(scaled[:, :3] ** 2)) == pytest.approx(
        np.sqrt(np.mean(scaled[:, 3:] ** 2))
    )


# ----------------------------------------------------------------------------- CRB


def test_cramer_rao_report_against_direct_formulae(stewart, random_cands):
    mech, params = stewart
    J = random_cands.jacobians[:18]
    Jv = random_cands.jacobians[18:40]
    noise = pincal.NoiseModel(0.01, 0.02)
    rep = cramer_rao_from_jacobian(J, random_cands.components, noise, Jv, params.names)
    sig = np.array([1e-5] * 3 + [2e-5] * 3)
    Jw = (J / sig[:, None]).reshape(-1, 42)
    C = np.linalg.inv(Jw.T @ Jw)
    np.testing.assert_allclose(rep.covariance, C, rtol=1e-6, atol=1e-9 * np.abs(C).max())
    np.testing.assert_allclose(rep.std, np.sqrt(np.diag(C)), rtol=1e-6)
    # predicted validation RMS: Monte Carlo of the linear error model
    rng = np.random.default_rng(1)
    dx = rng.multivariate_normal(np.zeros(42), C, size=4000)
    dp = np.einsum("vij,sj->svi", Jv[:, :3], dx)
    mc = np.sqrt(np.mean(np.sum(dp**2, axis=2)))
    assert rep.validation_position_rms == pytest.approx(mc, rel=0.05)
    assert rep.rank == 42 and "Cramér–Rao" in rep.summary()
    # the mechanism-level report agrees
    rep2 = cramer_rao(mech, params, random_cands.q_act[:18], noise, random_cands.q_act[18:40])
    np.testing.assert_allclose(rep2.std, rep.std, rtol=1e-6)
    assert rep2.validation_orientation_rms == pytest.approx(rep.validation_orientation_rms)
    with pytest.raises(UnidentifiableError):
        cramer_rao_from_jacobian(J[:5], random_cands.components, noise)
    with pytest.raises(PincalError, match="positive std"):
        cramer_rao_from_jacobian(J, random_cands.components, pincal.NoiseModel(0.01, 0.0))


def test_efficiency_of_draws_from_the_bound_is_one():
    rng = np.random.default_rng(2)
    A = rng.standard_normal((5, 5))
    C = A @ A.T + np.eye(5)
    e = rng.multivariate_normal(np.zeros(5), C, size=4000)
    eff = efficiency(e, C)
    assert abs(eff.efficiency - 1.0) < 4 * eff.efficiency_se
    assert eff.efficiency_se < 0.05
    eff2 = efficiency(2.0 * e, C)  # twice the error: a quarter of the efficiency
    assert eff2.efficiency == pytest.approx(eff.efficiency / 4)


# ----------------------------------------------------------------------------- selection


def test_select_poses_restarts_keep_the_best(random_cands):
    sc = DesignScaling(rows="noise", position_std=1e-5, orientation_std=1e-5)
    d1 = select_poses(random_cands, 18, "O1", sc, rng=0, restarts=1)
    d3 = select_poses(random_cands, 18, "O1", sc, rng=0, restarts=3)
    assert d3.selection.value >= d1.selection.value
    assert np.all(np.diff(d3.selection.history) >= 0)
    Jsel = sc.apply(random_cands.jacobians[d3.indices], random_cands.components).J
    assert observability(Jsel).O1 == pytest.approx(d3.selection.value, rel=1e-9)
    np.testing.assert_array_equal(d3.q_act, random_cands.q_act[d3.indices])
    g = select_poses(random_cands, 18, "O3", sc, method="greedy")
    assert len(np.unique(g.indices)) == 18
    with pytest.raises(UnknownNameError):
        select_poses(random_cands, 18, "O1", sc, method="anneal")


@pytest.mark.slow
def test_o1_poses_beat_random_poses(stewart, random_cands):
    """The core claim, small: O1-optimised 18 poses identify better than 18 random ones."""
    mech, params = stewart
    noise = pincal.NoiseModel(0.01, 0.01)
    sc = DesignScaling(rows="noise", position_std=1e-5, orientation_std=1e-5)
    best = select_poses(random_cands, 18, "O1", sc, rng=0, restarts=2)
    rng = np.random.default_rng(5)
    crb_best = cramer_rao(mech, params, best.q_act, noise)
    sq = {"O1": [], "random": []}
    crb_random = []
    for _ in range(10):
        q_rand = pincal.sample_actuators(mech, 18, rng)
        crb_random.append(cramer_rao(mech, params, q_rand, noise).rms_std)
        true = rng.normal(0.0, 3e-4, len(params))
        actual = params.apply(mech, true)
        seed = int(rng.integers(2**31))
        for name, q in (("O1", best.q_act), ("random", q_rand)):
            meas = pincal.simulate_measurements(actual, q, noise, np.random.default_rng(seed))
            res = pincal.identify(mech, params, meas)
            sq[name].append(np.mean((res.values - true) ** 2))
    # predicted (exact, no noise) and achieved (Monte Carlo) both favour O1
    assert np.mean(crb_random) / crb_best.rms_std > 1.2
    ratio = np.sqrt(np.mean(sq["random"]) / np.mean(sq["O1"]))
    assert ratio > 1.0  # predicted ≈ 1.6; 10 repetitions keep the MC noise well below


def test_o1_poses_have_a_smaller_bound_than_random_poses(stewart, random_cands):
    """The core claim's prediction in the fast lane (no fits): O1's 18 poses beat random ones."""
    mech, params = stewart
    noise = pincal.NoiseModel(0.01, 0.01)
    sc = DesignScaling(rows="noise", position_std=1e-5, orientation_std=1e-5)
    best = select_poses(random_cands, 18, "O1", sc, rng=0, restarts=2)
    rng = np.random.default_rng(5)
    crb_best = cramer_rao(mech, params, best.q_act, noise).rms_std
    crb_random = [
        cramer_rao(mech, params, pincal.sample_actuators(mech, 18, rng), noise).rms_std
        for _ in range(10)
    ]
    assert min(crb_random) > crb_best and np.mean(crb_random) / crb_best > 1.2


# ----------------------------------------------------------------------------- writing, CLI


def test_write_poses_and_cli(tmp_path, stewart, random_cands):
    mech, _ = stewart
    sc = DesignScaling(rows="K", K=0.25)
    d = select_poses(random_cands, 18, "O1", sc, rng=1)
    csv_path, cmd_path, json_path = write_pose_design(d, tmp_path / "p.csv")
    poses = read_poses(csv_path)
    _, q_rows = read_commands(cmd_path, mech)
    assert len(poses) == len(q_rows) == 18
    T = mech.forward(q_rows[0])
    np.testing.assert_allclose(poses[0].translation, T.translation, atol=1e-9)
    np.testing.assert_allclose(poses[0].rotation, T.rotation, atol=1e-9)
    rec = json.loads(json_path.read_text())
    assert rec["index"] == "O1" and rec["history"][-1] == pytest.approx(d.selection.value)
    assert "K = 250 mm" in rec["scaling"]

    from pincal.cli import main

    out = tmp_path / "cli" / "poses.csv"
    result = CliRunner().invoke(
        main,
        ["poses", "stewart_6ups", "--count", "18", "--index", "O1", "--candidates", "random:40",
         "--out", str(out), "--restarts", "1"],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    assert "wrote" in result.output and "Cramér–Rao" in result.output
    rec = json.loads(out.with_suffix(".json").read_text())
    assert len(rec["candidate_indices"]) == 18 and len(rec["predicted_std"]) == 42
    assert np.all(np.diff(rec["history"]) >= 0)
    bad = CliRunner().invoke(main, ["poses", "stewart_6ups", "--candidates", "sobol:3"])
    assert bad.exit_code == 1 and "grid:LEVELS" in bad.output


# ----------------------------------------------------------------------------- identifiability


def test_full_set_identifiability_lists_the_unidentifiable_directions(stewart):
    mech, _ = stewart
    full = pincal.parameters(mech, "full")
    q = pincal.sample_actuators(mech, 40, np.random.default_rng(0))
    J = pincal.identification_jacobian(mech, full, q)
    ident = pincal.sensitivity.analyse_jacobian(J, full.names)
    s = np.linalg.svd(J, compute_uv=False)
    # the stacked Jacobian has a clear gap (≥ 1e6) right after its numerical rank
    assert ident.rank == np.linalg.matrix_rank(J, tol=1e-8 * s[0])
    assert s[ident.rank - 1] / s[ident.rank] > 1e6
    # 6 legs × (base joint xyz, platform joint xyz, leg offset) + measured-frame pose
    assert ident.rank == 48 and len(ident.base) == 48
    names = set(ident.unidentifiable_names)
    # rotations of the U-joint placements about any axis do not move a point-contact leg
    for leg in range(1, 7):
        assert {f"leg{leg}_u1.rx", f"leg{leg}_u1.ry", f"leg{leg}_u1.rz"} <= names
    lines = "\n".join(ident.describe())
    assert "leg1_u1.rx is not identifiable (it has no effect on the measurements)" in lines
    assert "leg1_u2.ty is not identifiable (absorbed by" in lines
    # the preset is exactly identifiable
    stewart42 = pincal.parameters(mech, "stewart42")
    J42 = J[:, [full.index(n) for n in stewart42.names]]
    assert pincal.sensitivity.analyse_jacobian(J42, stewart42.names).full_rank


def test_identify_reduces_or_refuses_a_rank_deficient_set(stewart):
    mech, _ = stewart
    params = pincal.parameters(mech, ["leg1_u1.tx", "leg1_u1.rx", "leg1_slide.offset"])
    q = pincal.sample_actuators(mech, 8, np.random.default_rng(4))
    true = np.array([2e-4, 1e-3, -1e-4])
    meas = pincal.simulate_measurements(params.apply(mech, true), q)
    with pytest.raises(UnidentifiableError, match="leg1_u1.rx"):
        pincal.identify(mech, params, meas, reduce=False)
    res = pincal.identify(mech, params, meas)
    assert "base parameters" in res.message and res.fixed == ("leg1_u1.rx",)
    np.testing.assert_allclose(res.values, true[[0, 2]], atol=1e-9)
