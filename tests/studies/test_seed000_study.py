"""Seed-000 study (scripts/studies/stewart_pose_selection.py): Monte-Carlo ratios vs the bound.

In the linear regime of the study (0.5 mm errors, Gauss–Newton to convergence) the
expected mean-square errors are the Cramér–Rao ones, so the ratio Jz ÷ Jzg of the
Cramér–Rao predictions is what the Monte-Carlo ratio estimates. The fast tests check
that on a reduced configuration and check that the README table is consistent; the
slow one recomputes the README's Cramér–Rao columns with the full configuration.
"""

from __future__ import annotations

import importlib.util
import re
import sys
from pathlib import Path

import numpy as np
import pytest

import pincal
from pincal.design import (
    DesignScaling,
    characteristic_length,
    efficiency,
    grid_candidates,
    select_poses,
)
from pincal.model import COMPONENTS

ROOT = Path(__file__).resolve().parents[2]
_spec = importlib.util.spec_from_file_location(
    "stewart_pose_selection", ROOT / "scripts" / "studies" / "stewart_pose_selection.py"
)
study = importlib.util.module_from_spec(_spec)
sys.modules[_spec.name] = study  # dataclasses look their module up
_spec.loader.exec_module(study)

QUANTITIES = ("P", "θ", "S")


def readme_table() -> dict[str, dict[str, tuple[float, float, float]]]:
    """{index: {quantity: (Monte-Carlo ratio, its SE, Cramér–Rao ratio)}} of docs/studies.md."""
    text = (ROOT / "docs" / "studies.md").read_text(encoding="utf-8")
    section = text.split("### Seed 000", 1)[1].split("\n### ", 1)[0]
    rows = {}
    for line in section.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if not re.fullmatch(r"O[1-5]", cells[0]):
            continue
        mc = [tuple(float(v) for v in c.split("±")) for c in cells[1:4]]
        crb = [float(c) for c in cells[4:7]]
        rows[cells[0]] = {q: (*mc[k], crb[k]) for k, q in enumerate(QUANTITIES)}
    return rows


def _designs(cands, index, K, restarts):
    out = {}
    for name, k in (("Jz", 1e-3), ("Jzg", K)):
        d = select_poses(cands, 18, index, DesignScaling(rows="K", K=k), rng=0, restarts=restarts)
        out[name] = d
    return out


def _validation(nominal, params, count, seed):
    q_val = pincal.sample_actuators(nominal, count, np.random.default_rng(seed))
    Jv = pincal.identification_jacobian(nominal, params, q_val, components=COMPONENTS)
    return q_val, Jv.reshape(count, 6, len(params))


def test_readme_table_monte_carlo_agrees_with_the_bound_within_its_standard_errors():
    table = readme_table()
    assert sorted(table) == ["O1", "O2", "O3", "O4", "O5"]
    for index, row in table.items():
        for q, (mc, se, crb) in row.items():
            assert 0 < se < 0.1, (index, q, se)  # enough repetitions to separate claims
            assert abs(mc - crb) <= 3 * se, (index, q, mc, se, crb)


@pytest.mark.slow  # ~20 s of Monte Carlo; the README table's check above stays fast
def test_monte_carlo_ratio_estimates_the_bound_ratio_reduced():
    """Reduced but complete: 3-level grid, O3, 20 paired repetitions at one noise level."""
    nominal, params = study._model()
    cands = grid_candidates(nominal, params, 3)
    K = characteristic_length(cands.jacobians, cands.components)
    designs = _designs(cands, "O3", K, restarts=1)
    q_val, Jv = _validation(nominal, params, 20, 5)
    designs_J = {k: d.candidates.jacobians for k, d in designs.items()}
    bound = study.bound_ratios(designs_J, cands.components, Jv, params)
    res = study.run_mc(
        {k: d.q_act for k, d in designs.items()},
        20,
        study.stream(0, "O3"),
        q_val,
        levels=(1,),
    )
    mc = study.mc_ratios(res, (1,))
    for q in QUANTITIES:
        ratio, se = mc[q]
        assert 0 < se < 0.25, (q, se)
        assert abs(ratio - bound[q]) <= 3 * se, (q, ratio, se, bound[q])
    # the estimator is efficient (whitened, unit-free form) for both designs
    for key, d in designs_J.items():
        crb = study.crb_for(d, cands.components, 1, Jv, params)
        eff = efficiency(np.array(res[(key, 1)].param_err), crb.covariance)
        assert abs(eff.whitened - 1.0) <= 3 * eff.whitened_se, (key, eff.whitened)


@pytest.mark.slow  # a 2-worker Dask cluster and 2 × 4 repetitions
def test_the_monte_carlo_is_bit_identical_on_two_dask_workers():
    """Issue 41: the study's table reproduces bit for bit on 1 process and 2 Dask workers."""
    pytest.importorskip("distributed")
    nominal, params = study._model()
    cands = grid_candidates(nominal, params, 3)
    designs = {k: d.q_act for k, d in _designs(cands, "O1", 0.3, restarts=1).items()}
    q_val, _ = _validation(nominal, params, 10, 5)
    runs = [
        study.run_mc(designs, 4, study.stream(0, "O1"), q_val, levels=(1,), scheduler=where)
        for where in (None, "local:2")
    ]
    for key, serial in runs[0].items():
        dask = runs[1][key]
        assert serial.pos_ms == dask.pos_ms and serial.rot_ms == dask.rot_ms
        pairs = zip(serial.param_err, dask.param_err, strict=True)
        assert all(np.array_equal(a, b) for a, b in pairs)
    assert len(runs[0][("Jz", 1)].pos_ms) == 4


def test_indices_use_independent_seed_streams():
    states = {
        i: study.stream(0, i).generate_state(4).tolist()
        for i in ("O1", "O2", "O3", "O4", "O5", "random")
    }
    assert len({tuple(s) for s in states.values()}) == len(states)
    assert study.stream(0, "O2").generate_state(4).tolist() == states["O2"]  # reproducible


def test_pooled_mean_squares_are_divided_by_the_noise_variance():
    res = {
        ("a", lv): study.Outcome(
            [(NOISE * 1e-3) ** 2] * 3, [2 * (NOISE * 1e-3) ** 2] * 3, [np.zeros(2)] * 3
        )
        for lv, (NOISE, _) in enumerate(study.NOISE_LEVELS)
    }
    np.testing.assert_allclose(study.pooled(res, "a", "P", range(3)), np.ones(9))
    np.testing.assert_allclose(study.pooled(res, "a", "θ", range(3)), 2 * np.ones(9))


@pytest.mark.slow
def test_readme_bound_ratios_are_those_of_the_full_configuration():
    """4-level grid, 3 exchange restarts, seed 0, 60 validation poses (as the script)."""
    table = readme_table()
    nominal, params = study._model()
    cands = grid_candidates(nominal, params, 4)
    K = characteristic_length(cands.jacobians, cands.components)
    q_val = pincal.sample_actuators(nominal, study.N_VALIDATION, np.random.default_rng(1000))
    Jv = pincal.identification_jacobian(nominal, params, q_val, components=COMPONENTS)
    Jv = Jv.reshape(study.N_VALIDATION, 6, len(params))
    for index, row in table.items():
        designs = _designs(cands, index, K, restarts=3)
        designs_J = {k: d.candidates.jacobians for k, d in designs.items()}
        bound = study.bound_ratios(designs_J, cands.components, Jv, params)
        for q in QUANTITIES:
            assert bound[q] == pytest.approx(row[q][2], abs=0.006), (index, q, bound[q])
