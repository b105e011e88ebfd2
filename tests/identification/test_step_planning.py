"""Sensitivity-planned step identification and wedge compensation (seed 002)."""

from __future__ import annotations

import dataclasses
import shutil
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pincal
from pincal.identification import StepPlanningOptions, identify
from pincal.machines import (
    PATENT_PRESET_NAMES,
    WedgeGeometry,
    wedge_compensation,
    wedge_forward,
    wedge_inverse,
    wedge_urdf,
    wedge_workspace_grid,
)
from pincal.measure import NoiseModel
from pincal.sensitivity import global_sensitivity

MODEL_DIR = Path(__file__).resolve().parents[2] / "models" / "wedge3"
BOX = ((-0.05, 0.05), (-0.002, 0.002), (-0.01, 0.01))
# drawn errors [m, rad] in preset order: offsets, bar ends, wedge-slide rotations
ERRORS = np.array([2e-5, -3e-5, 1.5e-5, -2.5e-5, 1e-5, 4e-4, -3e-4])


@pytest.fixture(scope="module")
def setup():
    mech = pincal.load_mechanism("wedge3")
    params = pincal.parameters(mech, "patent")
    actual = params.apply(mech, ERRORS)
    q = wedge_inverse(wedge_workspace_grid(*BOX, n=3), WedgeGeometry.nominal())
    meas = pincal.simulate_measurements(actual, q, None, np.random.default_rng(0))
    # exact data with a declared σ (1 µm, 1 µrad), so no noise is estimated from ~0 residuals
    meas = dataclasses.replace(meas, noise=NoiseModel(1e-3, 1e-3))
    sens = global_sensitivity(mech, params, q)
    planned = identify(
        mech, params, meas, "step-planned", options=StepPlanningOptions(sensitivity=sens)
    )
    return mech, params, meas, planned


def _patent_pose(mech: pincal.Mechanism, q_act: np.ndarray) -> np.ndarray:
    """(x, z, α) of the bar centre; the measured ry is −α (models/wedge3/README.md)."""
    T = mech.forward(q_act)
    return np.array([T.translation[0], T.translation[2], -pin.log3(T.rotation)[1]])


def test_converges_to_gauss_newton_on_noise_free_data(setup) -> None:
    mech, params, meas, planned = setup
    gn = pincal.identify(mech, params, meas, "gauss-newton")
    assert planned.success, planned.message
    assert planned.method == "step-planned"
    np.testing.assert_allclose(planned.values, gn.values, atol=1e-11)
    np.testing.assert_allclose(planned.values, ERRORS, atol=1e-11)
    assert planned.fixed == ()
    assert np.all(np.diff(planned.cost_history) <= 0)


def test_steps_are_planned_by_sensitivity(setup) -> None:
    """The first planned step differs from the Gauss–Newton step (damped in sensitivity
    units) and the steps add up to the identified values."""
    _, _, _, planned = setup
    np.testing.assert_allclose(planned.extras.steps.sum(axis=0), planned.values, atol=1e-15)
    assert planned.iterations >= 2


def test_compensation_keeps_the_closed_form(setup) -> None:
    _, params, _, planned = setup
    assert params.names == PATENT_PRESET_NAMES
    geom = wedge_compensation(params.names, planned.values)
    rng = np.random.default_rng(3)
    poses = rng.uniform(*np.array(BOX).T, size=(8, 3))
    for q_act in wedge_inverse(poses, geom):
        np.testing.assert_allclose(
            wedge_forward(q_act, geom), _patent_pose(planned.calibrated, q_act), atol=1e-12
        )
    # and the compensated geometry regenerates a model of the same structure
    np.testing.assert_allclose(
        wedge_forward(np.zeros(3), geom), _patent_pose(planned.calibrated, np.zeros(3)), atol=1e-12
    )


def test_compensated_urdf_has_the_calibrated_kinematics(setup, tmp_path) -> None:
    _, params, _, planned = setup
    geom = wedge_compensation(params.names, planned.values)
    (tmp_path / "wedge3.urdf").write_text(wedge_urdf(geom))
    shutil.copy(MODEL_DIR / "wedge3.yaml", tmp_path / "wedge3.yaml")
    rebuilt = pincal.load_mechanism(tmp_path / "wedge3.urdf")
    for q_act in np.random.default_rng(4).uniform(-0.01, 0.01, size=(5, 3)):
        np.testing.assert_allclose(
            _patent_pose(rebuilt, q_act), _patent_pose(planned.calibrated, q_act), atol=1e-12
        )


def test_compensation_rejects_foreign_names() -> None:
    with pytest.raises(pincal.ParameterError, match="no patent meaning"):
        wedge_compensation(["q0.offset", "bar_rev.offset"], np.zeros(2))
