"""Newton polishing: closed configurations are exact to round-off, not only to ``tol``."""

from __future__ import annotations

import numpy as np

from pincal.model import SolverOptions, load_mechanism, sample_actuators
from tests.open_world.machines import MJCF


def _worst_closure(mech) -> float:
    rows = sample_actuators(mech, 30, np.random.default_rng(11))
    return max(float(np.max(np.abs(mech.closure_residual(mech.configuration(r))))) for r in rows)


def test_configurations_close_the_loops_to_round_off():
    mech = load_mechanism(MJCF / "fourbar.xml")
    assert mech.options.polish_steps > 0
    assert _worst_closure(mech) <= 1e-15  # measured 4.2e-13 when stopping at tol = 1e-12
    unpolished = load_mechanism(MJCF / "fourbar.xml", options=SolverOptions(polish_steps=0))
    assert 1e-15 < _worst_closure(unpolished) <= unpolished.options.tol
