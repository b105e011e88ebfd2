"""Machine style: a five-bar exported from CAD (tests/open_world/cad_machines.py): world-
aligned link frames, numbers rounded to 7 digits, the planar loop closed by a 3-D weld
whose redundant rows miss by ~1e-8 m (issue 36, item 2: such exports were refused with
"residual 0.000 mm")."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from pincal.errors import ClosureError
from pincal.model import load_mechanism, sample_actuators
from tests.open_world import acceptance
from tests.open_world.cad_machines import fivebar_cad
from tests.open_world.machines import write_machine


@pytest.fixture(scope="module")
def model(tmp_path_factory) -> Path:
    return write_machine(tmp_path_factory.mktemp("m"), "fivebar_cad", *fivebar_cad())


@pytest.fixture(scope="module")
def mech(model):
    return load_mechanism(model)


def test_the_redundant_loop_closes_in_the_least_squares_sense_and_says_so(mech):
    r = np.abs(mech.closure_residual(mech.q_home))
    assert 1e-9 < r.max() < 1e-7  # the rounded geometry: no exact closure
    said = [n for n in mech.notes if "over-constrained" in n]
    assert len(said) == 1 and "tip_l ↔ tip_r" in said[0] and "least-squares" in said[0]
    m = re.search(r"closed to ([0-9.e+-]+) m", said[0])
    assert m and float(m.group(1)) == pytest.approx(r.max(), rel=0.05)


def test_forward_kinematics_closes_the_rest_exactly(mech):
    rows = sample_actuators(mech, 12, np.random.default_rng(3))
    Q = mech.configurations(rows)
    for q, row in zip(Q, rows, strict=True):
        r = mech.closure_residual(q)
        J = mech.closure_jacobian(q)[:, mech.free_dofs]
        # the in-range part of the residual is closed to the usual 1e-12
        removable = J @ np.linalg.lstsq(J, r, rcond=1e-10)[0]
        assert np.max(np.abs(removable)) <= 1e-12
        assert np.max(np.abs(r)) < 1e-7
        assert np.allclose(mech.configuration(row), q, atol=1e-10)


def test_noise_free_recovery(mech):
    acceptance.check_recovery(mech)


def test_a_loop_that_misses_by_more_is_refused_naming_the_residual(tmp_path):
    urdf, side = fivebar_cad()
    # a 0.05 mm step along the joint axes in the fixed tip: beyond 1e-6 of the size
    old = re.search(r'name="tip_r_joint".*?<origin xyz="([^"]+)"', urdf).group(1)
    xyz = np.array(old.split(), dtype=float) + 5e-5 * np.array([0.0, -0.4017, 0.9158])
    urdf = urdf.replace(old, " ".join(f"{x:.7g}" for x in xyz))
    with pytest.raises(ClosureError) as err:
        load_mechanism(write_machine(tmp_path, "fivebar_cad", urdf, side))
    msg = str(err.value)
    assert "0.000 mm" not in msg and "µm" in msg
    assert "over-constrained (its 6 rows have rank 3)" in msg
