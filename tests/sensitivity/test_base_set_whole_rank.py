"""A base set is a base: its own Jacobian has full rank, not only each column's part.

The xarm7 (example-robot-data) writes its joints' rpy as ±1.5708: its in-axis offsets
are each ~3e-6 off the span of the columns before them, so the in-order choice kept
them, and the 34 chosen columns had rank 29 (five singular values at 1e-16): `pincal
poses xarm7` was refused with "Jacobian has rank 29 < 34 parameters".
"""

from __future__ import annotations

import numpy as np
import pytest

import pincal
from pincal.model import example_robot_names, sample_actuators
from pincal.sensitivity import base_set, identification_jacobian, jacobian_rank


@pytest.mark.skipif(
    "xarm7" not in example_robot_names(), reason="xarm7 is not in this example-robot-data"
)
def test_the_xarm7_base_set_has_the_rank_it_counts():
    mech = pincal.load_mechanism("xarm7")
    chosen = base_set(mech)
    assert len(chosen.params) == chosen.analysis.rank == 34
    rows = sample_actuators(mech, 60, np.random.default_rng(7))  # other poses than its own
    assert jacobian_rank(identification_jacobian(mech, chosen.params, rows)) == 34
