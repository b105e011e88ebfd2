"""identification.json has one reader (pincal.io.read_identification); the report renders
the IdentificationResult it returns and checks its own annotations."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import pincal
from pincal.errors import CalibrationDirectoryError, ReportError
from pincal.identification import IdentificationRecord, identify, result_to_dict
from pincal.io import read_identification
from pincal.report import calibration_report

DEMO_01 = {  # written by `pincal demo` of pincal 0.1
    "model": "stewart_6ups",
    "preset": "stewart42",
    "units": "SI (m, rad)",
    "parameters": [
        {"name": "leg1.tx", "value": 1e-4, "std": 1e-5, "unit": "m", "true": 1.1e-4},
        {"name": "leg1.rx", "value": -2e-4, "std": 3e-5, "unit": "rad", "true": -2e-4},
    ],
    "validation_before": {"rms_position_mm": 1.0, "max_position_mm": 2.0},
    "validation_after": {"rms_position_mm": 0.01, "max_position_mm": 0.02},
    "reduced_chi2": 0.9,
    "iterations": 5,
    "cost_history": [1.0, 1e-3, 1e-6],
    "message": "converged",
}


V2_FILE = Path(__file__).parents[1] / "identification" / "data" / "rrr3_identification_v2.json"
V2 = json.loads(V2_FILE.read_text())


def test_pincal_01_demo_file_is_refused_with_what_to_do(tmp_path):
    (tmp_path / "identification.json").write_text(json.dumps(DEMO_01))
    with pytest.raises(CalibrationDirectoryError, match=r"written by pincal 0\.1"):
        read_identification(tmp_path / "identification.json")
    with pytest.raises(ReportError, match=r"written by pincal 0\.1.*re-run `pincal calibrate`"):
        calibration_report(tmp_path)


def test_a_version_2_file_gives_its_report(tmp_path):
    (tmp_path / "identification.json").write_text(json.dumps(V2))
    res = read_identification(tmp_path / "identification.json")
    assert isinstance(res, IdentificationRecord) and len(res.identified_names) == 21
    md = calibration_report(tmp_path).markdown.read_text()
    assert "Model rrr3" in md and "| base1.offset |" in md
    assert '<img src="data:image/png;base64,' in calibration_report(tmp_path).html.read_text()


def test_result_written_by_to_dict_is_reported(tmp_path, stewart, stewart42, stewart_poses):
    truth = np.random.default_rng(3).normal(0.0, 3e-4, len(stewart42))
    noise = pincal.NoiseModel(0.01, 0.02)
    actual = stewart42.apply(stewart, truth)
    meas = pincal.simulate_measurements(actual, stewart_poses, noise, np.random.default_rng(4))
    res = identify(stewart, stewart42, meas, "lm")
    notes = {"truth": dict(zip(stewart42.names, truth, strict=True))}
    (tmp_path / "identification.json").write_text(json.dumps(result_to_dict(res, notes)))
    back = read_identification(tmp_path / "identification.json")
    np.testing.assert_array_equal(back.values, res.values)
    md = calibration_report(tmp_path).markdown.read_text()
    assert all(f"| {n} |" in md for n in stewart42.names) and "Model stewart_6ups" in md
    assert f"{res.iterations} iterations" in md


def test_bad_annotations_are_refused(tmp_path):
    path = tmp_path / "identification.json"
    path.write_text(json.dumps({**V2, "validation_errors": {"before": {}}}))
    read_identification(path)  # a valid result; the annotation is the report's to check
    with pytest.raises(ReportError, match="'before' and 'after'"):
        calibration_report(tmp_path)
    path.write_text(json.dumps({**V2, "version": 99}))
    with pytest.raises(CalibrationDirectoryError, match="version 99"):
        read_identification(path)
    with pytest.raises(ReportError, match="version 99"):
        calibration_report(tmp_path)
    path.unlink()
    with pytest.raises(ReportError, match="identification.json .* does not exist"):
        calibration_report(tmp_path)
