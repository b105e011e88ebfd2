"""Inverse kinematics refuses imposed components the actuators cannot move independently
(issue 36).

The planar five-bar (motors about z, tip in the x y plane) declared as measuring [x, z]:
z moves with neither motor. Before: ``inverse`` of a pose from ``forward`` returned
commands 0.51 and 0.64 rad away from the ones that made it, silently (x and z were met).
It now raises UnreachablePoseError naming the components and ones that would fix the
commands. Imposing fewer components than actuators, each moved independently, stays
allowed (a compensation of chosen components: the neck imposing its roll only).
"""

from __future__ import annotations

import logging

import numpy as np
import pinocchio as pin
import pytest

from pincal.errors import UnreachablePoseError
from pincal.model import load_mechanism, sample_actuators
from tests.open_world import linkage_machines as lm
from tests.open_world import machines as m


def _fivebar(folder, measured):
    logging.disable(logging.WARNING)  # the motors' ranges found, not declared
    try:
        return load_mechanism(m.copy_machine(folder, "fivebar", measured=measured))
    finally:
        logging.disable(logging.NOTSET)


def test_dependent_components_are_refused_with_what_to_impose(tmp_path):
    mech = _fivebar(tmp_path, ["x", "z"])
    for row in sample_actuators(mech, 3, np.random.default_rng(0)):
        with pytest.raises(UnreachablePoseError) as info:
            mech.inverse(mech.forward(row))
        text = str(info.value)
        assert "\n" not in text
        assert "imposed components [x, z] are locally dependent" in text
        assert "only 1 independent direction(s)" in text and "impose [x, y] instead" in text


def test_independent_components_still_invert(tmp_path):
    mech = _fivebar(tmp_path, ["x", "y"])
    for row in sample_actuators(mech, 3, np.random.default_rng(0)):
        assert np.max(np.abs(mech.inverse(mech.forward(row)) - row)) <= 1e-9


def test_fewer_independent_components_than_actuators_are_allowed(tmp_path):
    sidecar = {**lm.NECK_SIDECAR, "measured": ["rx"]}
    neck = load_mechanism(lm.write_mjcf(tmp_path, "neck", lm.mjcf_neck(), sidecar))
    row = sample_actuators(neck, 1, np.random.default_rng(2))[0]
    T = neck.forward(row)
    got = neck.forward(neck.inverse(T))
    assert abs(pin.log3(got.rotation.T @ T.rotation)[0]) <= 1e-9  # the roll is met
