"""identification.json: one writer and one reader (result_to_dict, result_from_dict)."""

from __future__ import annotations

import json

import numpy as np
import pytest

import pincal
from pincal.errors import ReportError
from pincal.identification import (
    FORMAT_VERSION,
    IdentificationResult,
    QPSOExtras,
    QPSOOptions,
    StepPlanningExtras,
    StepPlanningOptions,
    identify,
    result_from_dict,
    result_to_dict,
)


def _roundtrip(result: IdentificationResult, notes=None) -> tuple[dict, IdentificationResult]:
    doc = json.loads(json.dumps(result_to_dict(result, notes)))
    return doc, result_from_dict(doc)


def _same(a: IdentificationResult, b: IdentificationResult) -> None:
    assert a.names == b.names and a.units == b.units and a.method == b.method
    np.testing.assert_array_equal(a.full_values, b.full_values)
    np.testing.assert_array_equal(a.identified, b.identified)
    np.testing.assert_array_equal(a.std, b.std)
    np.testing.assert_array_equal(a.covariance, b.covariance)
    np.testing.assert_array_equal(a.residuals, b.residuals)
    np.testing.assert_array_equal(a.initial_values, b.initial_values)
    assert a.cost_history == b.cost_history and a.iterations == b.iterations
    assert (a.success, a.message, a.model, a.preset) == (b.success, b.message, b.model, b.preset)
    assert a.reduced_chi2 == b.reduced_chi2 and a.n_equations == b.n_equations
    for field in ("rms_position", "max_position", "rms_orientation", "max_orientation"):
        assert getattr(a.after, field) == pytest.approx(getattr(b.after, field), rel=1e-12)


def test_gauss_newton_result_roundtrip_with_held_parameters(stewart, stewart_poses):
    params = pincal.parameters(stewart, ["leg1_u1.tx", "leg1_u1.rz", "leg1_slide.offset"])
    truth = np.array([1e-4, 0.0, -2e-4])
    noise = pincal.NoiseModel(0.01, 0.02)
    meas = pincal.simulate_measurements(
        params.apply(stewart, truth), stewart_poses, noise, np.random.default_rng(0)
    )
    res = identify(stewart, params, meas)
    assert res.fixed == ("leg1_u1.rz",)
    notes = {"data": "m.csv", "truth": dict(zip(params.names, truth, strict=True))}
    doc, back = _roundtrip(res, notes)
    assert doc["version"] == FORMAT_VERSION and doc["held"][0]["name"] == "leg1_u1.rz"
    assert doc["parameters"][0]["true"] == 1e-4 and doc["identifiability"]["rank"] == 2
    _same(res, back)
    assert back.fixed == res.fixed and back.extras == res.extras
    assert back.annotations["data"] == "m.csv" and back.annotations["truth"]["leg1_u1.tx"] == 1e-4
    assert result_to_dict(back) == doc  # the reader keeps everything the writer wrote
    with pytest.raises(pincal.ParameterError, match="read from a file"):
        _ = back.params
    with pytest.raises(ReportError, match="overwrite"):
        result_to_dict(res, {"method": "x"})


def test_qpso_and_step_planning_extras_roundtrip():
    mech = pincal.load_mechanism("wedge3")
    params = pincal.parameters(mech, ["q0.offset", "q1.offset", "q2.offset"])
    q = pincal.sample_actuators(mech, 8, np.random.default_rng(2))
    meas = pincal.simulate_measurements(params.apply(mech, np.array([2e-5, -1e-5, 7e-6])), q)
    res = identify(mech, params, meas, "qpso-stepwise", options=QPSOOptions(6, 10, seed=1))
    _, back = _roundtrip(res)
    _same(res, back)
    assert isinstance(back.extras, QPSOExtras) and back.extras == res.extras
    planned = identify(mech, params, meas, "step-planned", options=StepPlanningOptions(workspace=q))
    _, back = _roundtrip(planned)
    _same(planned, back)
    assert isinstance(back.extras, StepPlanningExtras)
    np.testing.assert_array_equal(back.extras.steps, planned.extras.steps)
    np.testing.assert_array_equal(back.extras.weights, planned.extras.weights)


CALIBRATE_01 = {
    "model": "hexaslide_6pus",
    "preset": "kinematic",
    "data": "m.csv",
    "method": "gauss-newton",
    "poses": 2,
    "success": True,
    "message": "converged",
    "iterations": 4,
    "reduced_chi2": 1.1,
    "parameters": [
        {"name": "a.tx", "unit": "m", "value": 1e-4, "std": 1e-6},
        {"name": "a.rx", "unit": "rad", "value": -2e-4, "std": 3e-6},
    ],
    "fixed": ["a.rz"],
    "identifiability": {"parameters": 3, "rank": 2, "unidentifiable": ["a.rz"]},
    "residuals": {
        "before": {
            "rms_position_mm": 1.0,
            "max_position_mm": 2.0,
            "rms_orientation_mrad": None,
            "max_orientation_mrad": None,
        },
        "after": {"rms_position_mm": 0.001, "max_position_mm": 0.002},
        "per_pose_SI": [[1e-6, 0.0, -1e-6], [0.0, 2e-6, 0.0]],
    },
    "calibrated_urdf": "cal/hexaslide_6pus.urdf",
}


def test_pincal_01_calibrate_file_is_read():
    res = result_from_dict(CALIBRATE_01)
    assert res.names == ("a.tx", "a.rx", "a.rz") and res.fixed == ("a.rz",)
    assert res.units == ("m", "rad", "rad")
    np.testing.assert_array_equal(res.values, [1e-4, -2e-4])
    np.testing.assert_allclose(res.covariance, np.diag([1e-12, 9e-12]))
    assert res.after.max_position == pytest.approx(2e-6) and np.isnan(res.after.rms_orientation)
    assert res.residuals.shape == (2, 3) and res.iterations == 4 and res.reduced_chi2 == 1.1
    assert res.annotations["calibrated_urdf"] == "cal/hexaslide_6pus.urdf"


def test_newer_or_malformed_files_are_refused_with_the_reason():
    with pytest.raises(ReportError, match="version 3, written by a newer pincal"):
        result_from_dict({**CALIBRATE_01, "version": 3})
    with pytest.raises(ReportError, match="'model'"):
        result_from_dict({"parameters": []})
    bad = {**CALIBRATE_01, "parameters": [{"name": "a.tx", "value": 1.0, "std": "x"}]}
    with pytest.raises(ReportError, match=r"parameters\[0\].std"):
        result_from_dict(bad)
    with pytest.raises(ReportError, match="covariance must be 2×2"):
        result_from_dict({**CALIBRATE_01, "covariance": [[1.0]]})
