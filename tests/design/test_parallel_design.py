"""Candidate evaluation in parallel processes: the same candidates for any n_jobs."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest

import pincal
from pincal.design import candidate_set, evaluate_candidates, grid_candidates
from pincal.design._parallel import _rebuild, _recipe
from pincal.errors import PincalError


def _assert_same(one, two):
    np.testing.assert_array_equal(one.q_act, two.q_act)
    np.testing.assert_allclose(two.positions, one.positions, rtol=0, atol=1e-12)
    np.testing.assert_allclose(two.rotations, one.rotations, rtol=0, atol=1e-12)
    np.testing.assert_allclose(two.jacobians, one.jacobians, rtol=0, atol=1e-12)
    assert one.rejected == two.rejected and one.tried == two.tried


def test_a_rebuilt_mechanism_has_the_same_kinematics(stewart, stewart_poses):
    twin = _rebuild(_recipe(stewart))
    assert twin is not stewart and twin.name == stewart.name
    np.testing.assert_array_equal(twin.q_home, stewart.q_home)
    for q_act in stewart_poses[:5]:
        np.testing.assert_array_equal(
            twin.frame_placement(twin.configuration(q_act)).homogeneous,
            stewart.frame_placement(stewart.configuration(q_act)).homogeneous,
        )
    assert _rebuild(_recipe(stewart)) is twin  # rebuilt once per process


def test_an_applied_mechanism_is_rebuilt_with_its_errors(stewart, stewart42, stewart_poses):
    actual = stewart42.apply(stewart, np.full(len(stewart42), 2e-4))
    twin = _rebuild(_recipe(actual))
    q = stewart_poses[3]
    np.testing.assert_array_equal(
        twin.frame_placement(twin.configuration(q)).homogeneous,
        actual.frame_placement(actual.configuration(q)).homogeneous,
    )


@pytest.mark.parametrize("bad", [0, -2, 1.5, True, "2"])
def test_n_jobs_is_checked(stewart, stewart42, bad):
    with pytest.raises(PincalError, match="n_jobs"):
        evaluate_candidates(stewart, stewart42, [stewart.q_home[:6]], n_jobs=bad)


@pytest.mark.slow
def test_grid_candidates_in_two_processes_are_the_same(stewart, stewart42):
    one = grid_candidates(stewart, stewart42, 3, in_workspace=False)
    two = grid_candidates(stewart, stewart42, 3, in_workspace=False, n_jobs=2)
    assert len(one) > 100
    _assert_same(one, two)
    kept = grid_candidates(stewart, stewart42, 3, n_jobs=2)  # workspace filter after FK
    _assert_same(grid_candidates(stewart, stewart42, 3), kept)


@pytest.mark.slow
@pytest.mark.parametrize(("model", "preset"), [("hexaslide_6pus", "full"), ("ur10", "full")])
def test_random_candidates_in_two_processes_are_the_same(model, preset):
    mech = pincal.load_mechanism(model)
    params = pincal.parameters(mech, preset)
    one = candidate_set(mech, params, "random:60", np.random.default_rng(4))
    two = candidate_set(mech, params, "random:60", np.random.default_rng(4), n_jobs=2)
    assert len(one) == 60
    _assert_same(one, two)


@pytest.mark.slow
def test_poses_command_selects_the_same_poses_for_any_jobs(tmp_path):
    from click.testing import CliRunner

    from pincal.cli import main

    written = []
    runs = [("1", ["--jobs", "1"]), ("2", ["--jobs", "2"])]
    if importlib.util.find_spec("distributed") is not None:  # issue 41: one executor
        runs.append(("dask", ["--scheduler", "local:2"]))
    for name, where in runs:
        out = tmp_path / name / "p.csv"
        args = ["poses", "stewart_6ups", "--candidates", "grid:3", "--count", "12"]
        result = CliRunner().invoke(main, [*args, *where, "--out", str(out)])
        assert result.exit_code == 0, result.output
        written.append(out.read_bytes())
    assert all(w == written[0] for w in written[1:])
    bad = CliRunner().invoke(main, ["poses", "stewart_6ups", "--jobs", "0"])
    assert bad.exit_code != 0 and "jobs" in bad.output


def test_a_bad_scheduler_is_refused_before_any_work(tmp_path):
    from click.testing import CliRunner

    from pincal.cli import main

    out = tmp_path / "p.csv"
    res = CliRunner().invoke(main, ["poses", "stewart_6ups", "--scheduler", "local:0",
                                    "--out", str(out)])  # fmt: skip
    assert res.exit_code != 0 and not out.exists()
    assert "--scheduler: scheduler 'local:0'" in res.output and "local:2" in res.output
    assert "Traceback" not in res.output and "parameters" not in res.output  # no model loaded
