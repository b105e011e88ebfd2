"""Three linkage machines new to pincal (issue 36; writers in linkage_machines.py): a
robot neck (MJCF, two linear actuators, U-joint head, measured [rx, ry]), an
excavator-style arm (URDF, three cylinders, four planar loops, measured [x, z, ry]) and
a gripper finger (MJCF in degrees, two ``connect`` four-bars); a finger variant coupling
its joints by ``polycoef`` is refused in one line.

Exact-data recovery of ``base`` and ``full`` runs with the rest of the roster
(test_roster.py); the excavator's ``full`` set is a strict xfail whose reason (its
conditioning) is checked here.
"""

from __future__ import annotations

import logging

import numpy as np
import pinocchio as pin
import pytest

from pincal.errors import ModelFileError
from pincal.model import load_mechanism, sample_actuators
from pincal.sensitivity import identifiability, parameters
from tests.open_world import acceptance
from tests.open_world import linkage_machines as lm
from tests.open_world.roster import ROSTER

NAMES = {
    "neck": "MJCF robot neck, two linear actuators, U-joint head",
    "excavator": "URDF excavator-style arm, three cylinders, four planar loops",
    "finger": "MJCF gripper finger, two four-bars",
}
SHAPE = {  # mobility, actuated joints, measured components, closures
    "neck": (2, ("push_l", "push_r"), ("rx", "ry"), 2),
    "excavator": (3, ("boom_cyl", "stick_cyl", "bucket_cyl"), ("x", "z", "ry"), 4),
    "finger": (1, ("drive",), ("x", "z", "ry"), 2),
}


def _write(name: str, folder):
    return next(mc for mc in ROSTER if mc.name == NAMES[name]).write(folder)


@pytest.fixture(scope="module", params=list(NAMES))
def machine(request, tmp_path_factory):
    logging.disable(logging.WARNING)
    try:
        mech = load_mechanism(_write(request.param, tmp_path_factory.mktemp(request.param)))
    finally:
        logging.disable(logging.NOTSET)
    return request.param, mech


def test_loads_with_its_mobility(machine):
    name, mech = machine
    mobility, actuated, measured, loops = SHAPE[name]
    assert mech.mobility == mobility and tuple(mech.actuated) == actuated
    assert tuple(mech.measured_components) == measured and len(mech.closures) == loops
    assert np.max(np.abs(mech.closure_residual(mech.q_home))) <= 1e-12


def test_forward_inverse_forward(machine):
    _, mech = machine
    for row in sample_actuators(mech, 6, np.random.default_rng(5)):
        T = mech.forward(row)
        back = mech.inverse(T)
        assert np.max(np.abs(back - row)) <= 1e-9
        T2 = mech.forward(back)
        assert np.max(np.abs(T2.translation - T.translation)) <= 1e-12
        assert np.max(np.abs(pin.log3(T.rotation.T @ T2.rotation))) <= 1e-12


def test_identification_jacobian_matches_central_differences(machine):
    _, mech = machine
    # 16 of the identifiable set (a random error of the full preset may break a planar loop)
    assert acceptance.check_jacobian(mech, size=16) > 0.1


def test_excavator_full_set_is_as_ill_conditioned_as_its_xfail_says(tmp_path):
    """The reason of the roster's strict xfail (exact-data recovery of ``full`` to
    1.4e-9 > 1e-9): σ_min / σ_max of its identifiable set at the recovery's 30 poses."""
    logging.disable(logging.WARNING)
    try:
        mech = load_mechanism(_write("excavator", tmp_path))
    finally:
        logging.disable(logging.NOTSET)
    rows = sample_actuators(mech, 30, np.random.default_rng(11))
    ratios = {}
    for preset in ("base", "full"):
        ident = identifiability(mech, parameters(mech, preset), rows)
        s = ident.singular_values
        ratios[preset] = s[ident.rank - 1] / s[0]
    assert 1e-8 < ratios["full"] < 1e-7 and ratios["full"] < ratios["base"] < 1e-6, ratios


def test_polycoef_finger_is_refused_in_one_line(tmp_path):
    path = lm.write_mjcf(tmp_path, "finger_pc", lm.mjcf_finger(coupler=False), None)
    with pytest.raises(ModelFileError) as info:
        load_mechanism(path)
    text = str(info.value)
    assert "\n" not in text
    assert "<equality><joint> 'pip_follows_mcp'" in text and "polycoef '0 0.8 0 0 0'" in text
    assert "model the linkage that makes the coupling" in text


@pytest.mark.slow
@pytest.mark.parametrize("name", list(NAMES))
def test_a_noisy_campaign_reaches_the_cramer_rao_prediction(name, tmp_path):
    doc = acceptance.noisy_campaign(_write(name, tmp_path), tmp_path)
    after, predicted, _ = acceptance.prediction_ratio(doc)
    assert predicted is not None
    assert after <= 2.5 * predicted, (after, predicted)
    block = "position" if doc["after"]["rms_position_mm"] is not None else "orientation"
    unit = "mm" if block == "position" else "mrad"
    assert doc["before"][f"rms_{block}_{unit}"] > 5 * after  # the calibration did something
