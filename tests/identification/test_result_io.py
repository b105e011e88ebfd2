"""identification.json: one writer and one reader (result_to_dict, result_from_dict).

The reader gives an IdentificationRecord (no live parts); a file pincal wrote before the
record was split off (``data/rrr3_identification_v2.json``, written by ``pincal calibrate``
of commit d307e66) reads back to the same document, byte for byte, and the same report.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import pincal
from pincal.errors import ReportError
from pincal.identification import (
    FORMAT_VERSION,
    IdentifiabilitySummary,
    IdentificationRecord,
    IdentificationResult,
    QPSOExtras,
    QPSOOptions,
    StepPlanningExtras,
    StepPlanningOptions,
    identify,
    result_from_dict,
    result_to_dict,
)
from pincal.io import read_identification
from pincal.report import calibration_text

DATA = Path(__file__).parent / "data"


def _roundtrip(result: IdentificationResult, notes=None) -> tuple[dict, IdentificationRecord]:
    doc = json.loads(json.dumps(result_to_dict(result, notes)))
    return doc, result_from_dict(doc)


def _same(a: IdentificationRecord, b: IdentificationRecord) -> None:
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
    assert type(back) is IdentificationRecord and not hasattr(back, "params")
    assert back.identifiability_summary == res.identifiability_summary
    assert res.identifiability_summary == IdentifiabilitySummary.of(res.identifiability)
    assert res.params.names == ("leg1_u1.tx", "leg1_slide.offset")
    with pytest.raises(ReportError, match="overwrite"):
        result_to_dict(res, {"method": "x"})
    with pytest.raises(ReportError, match="overwrite"):
        result_to_dict(res, {"identifiability": {}})


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


def test_a_record_applied_to_its_nominal_model_is_the_calibrated_mechanism(
    stewart, stewart42, stewart_poses
):
    truth = np.random.default_rng(5).normal(0.0, 2e-4, len(stewart42))
    actual = stewart42.apply(stewart, truth)
    meas = pincal.simulate_measurements(actual, stewart_poses, pincal.NoiseModel(0.01, 0.02))
    res = identify(stewart, stewart42, meas)
    _, back = _roundtrip(res)
    mech = back.applied_to(stewart)
    for name, joint in res.calibrated.tree.joints.items():
        np.testing.assert_allclose(
            mech.tree.joints[name].origin.homogeneous, joint.origin.homogeneous, atol=1e-15
        )
    with pytest.raises(pincal.ParameterError, match="give the model it was identified for"):
        back.applied_to(pincal.load_mechanism("wedge3"))


def test_a_version_2_file_written_before_the_record_reads_and_writes_back_the_same():
    path = DATA / "rrr3_identification_v2.json"
    text = path.read_text()
    rec = read_identification(path)
    assert type(rec) is IdentificationRecord
    assert json.dumps(result_to_dict(rec), indent=1) + "\n" == text
    doc = json.loads(text)
    assert rec.names == tuple(doc["names"]) and len(rec.names) == 78
    assert rec.identified_names == tuple(p["name"] for p in doc["parameters"])
    np.testing.assert_array_equal(rec.values, [p["value"] for p in doc["parameters"]])
    np.testing.assert_array_equal(rec.covariance, doc["covariance"])
    assert rec.components == ("x", "y", "rz") and rec.residuals.shape == (15, 3)
    summary = rec.identifiability_summary
    assert summary is not None and (summary.rank, summary.parameters) == (21, 78)
    assert len(summary.explanation) == 57 and rec.weighting is not None
    # the report read back is the one `pincal calibrate` printed when it wrote the file
    report = (DATA / "rrr3_report_v2.txt").read_text()
    assert calibration_text(rec, {"data": "r.csv"}) == report


CALIBRATE_01 = {  # written by `pincal calibrate` of pincal 0.1 (no "version")
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
    "residuals": {"per_pose_SI": [[1e-6, 0.0, -1e-6], [0.0, 2e-6, 0.0]]},
}

V2 = json.loads((DATA / "rrr3_identification_v2.json").read_text())


def test_a_pincal_01_file_is_refused_with_what_to_do():
    with pytest.raises(ReportError, match=r"written by pincal 0\.1 .*re-run `pincal calibrate`"):
        result_from_dict(CALIBRATE_01)


def test_newer_or_malformed_files_are_refused_with_the_reason():
    with pytest.raises(ReportError, match="version 3, written by a newer pincal"):
        result_from_dict({**V2, "version": 3})
    with pytest.raises(ReportError, match="no longer reads"):
        result_from_dict({**V2, "version": 1})
    with pytest.raises(ReportError, match="'model'"):
        result_from_dict({"version": 2, "parameters": []})
    first = V2["parameters"][0]
    bad = {**V2, "parameters": [{**first, "std": "x"}, *V2["parameters"][1:]]}
    with pytest.raises(ReportError, match=r"parameters\[0\].std"):
        result_from_dict(bad)
    with pytest.raises(ReportError, match="covariance must be 21×21"):
        result_from_dict({**V2, "covariance": [[1.0]]})
    with pytest.raises(ReportError, match="'covariance'"):
        result_from_dict({k: v for k, v in V2.items() if k != "covariance"})
    with pytest.raises(ReportError, match="'identifiability' must be"):
        result_from_dict({**V2, "identifiability": {"rank": "7"}})
