"""Machine style: a Delta whose parallelograms are planar four-revolute loops closed by
``6d`` welds (machines.delta_4r): three closures of 18 rows of rank 9, and two more
welds of the platform to the wrists of legs 2 and 3.

Identifiability must not count parameters that break loop closure as identifiable.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pincal.model import load_mechanism, sample_actuators
from pincal.sensitivity import (
    closure_breaking,
    identifiability,
    identification_jacobian,
    parameters,
)
from tests.open_world import acceptance
from tests.open_world.machines import delta_4r, write_machine


@pytest.fixture(scope="module")
def model(tmp_path_factory) -> Path:
    return write_machine(tmp_path_factory.mktemp("m"), "delta4r", *delta_4r())


@pytest.fixture(scope="module")
def mech(model):
    return load_mechanism(model)


def _parallelogram_rows(mech) -> np.ndarray:
    rows, k = [], 0
    for c in mech.closures:
        if c.frame_a.startswith("rod_b_end"):
            rows += list(range(k, k + c.size))
        k += c.size
    return np.array(rows)


def test_three_6d_parallelogram_closures_have_18_rows_of_rank_9(mech):
    assert mech.mobility == 3 and len(mech.closures) == 5
    for q in mech.configurations(sample_actuators(mech, 3, np.random.default_rng(2))):
        Jc = mech.closure_jacobian(q)[:, mech.free_dofs]
        rows = _parallelogram_rows(mech)
        assert rows.size == 18
        assert np.linalg.matrix_rank(Jc[rows], tol=1e-9) == 9


def test_identifiability_does_not_count_closure_breaking_parameters(mech):
    full = parameters(mech, "full")
    rows = sample_actuators(mech, 30, np.random.default_rng(5))
    ident = identifiability(mech, full, rows)
    breaking = closure_breaking(mech, full, rows)
    assert breaking.sum() > 0
    assert set(ident.breaks_closure) == set(np.flatnonzero(breaking))
    assert breaking[ident.base].sum() == 0
    assert "break loop closure" in ident.summary()
    # the rank counts the closable columns only
    J = identification_jacobian(mech, full, rows)[:, ~breaking]
    norms = np.linalg.norm(J, axis=0)
    live = norms > 1e-12 * norms.max()
    s = np.linalg.svd(J[:, live] / norms[live], compute_uv=False)
    assert ident.rank == int(np.sum(s > 1e-8 * s[0]))
    assert set(parameters(mech, "base").names) <= {full.names[k] for k in np.flatnonzero(~breaking)}


def test_round_trip(mech):
    acceptance.check_round_trip(mech)


def test_jacobian_matches_central_differences(mech):
    acceptance.check_jacobian(mech)


def test_noise_free_recovery(mech):
    acceptance.check_recovery(mech)


@pytest.mark.slow
def test_simulate_calibrate_compensate(model, tmp_path):
    acceptance.check_cli(model, tmp_path)
