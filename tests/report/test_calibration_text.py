"""report.txt is rendered from the result (`pincal.report.calibration_text`), not from JSON.

The text of a live result and of the one read back from its identification.json by
`pincal.io.read_identification` must be the same, on a 6-D Stewart platform and on the
planar 3-RRR of tests/model/machines/rrr3 (measures x y rz), with declared noise.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import pincal
from pincal.identification import check_quality, identify, result_to_dict
from pincal.io import read_identification
from pincal.model import load_mechanism, sample_actuators
from pincal.report import calibration_text
from pincal.sensitivity import parameters

RRR3 = Path(__file__).resolve().parents[1] / "model" / "machines" / "rrr3"


def _fit(mech, params, seed: int):
    """A simulated identification with declared noise, and the gate's verdict on it."""
    rng = np.random.default_rng(seed)
    truth = rng.normal(0.0, 3e-4, len(params))
    noise = pincal.NoiseModel(0.01, 0.02)
    poses = sample_actuators(mech, 30, rng)
    meas = pincal.simulate_measurements(params.apply(mech, truth), poses, noise, rng)
    result = identify(mech, params, meas, noise={"position": 0.01, "orientation": 0.02})
    return result, check_quality(result, meas, mech=mech)


@pytest.mark.parametrize("machine", ["stewart", "rrr3"])
def test_text_of_the_result_read_back_equals_the_live_one(tmp_path, machine, stewart, stewart42):
    if machine == "stewart":
        mech, params = stewart, stewart42
    else:
        mech = load_mechanism(str(RRR3))
        params = parameters(mech, "base")
    result, verdict = _fit(mech, params, seed=5)
    notes = {"data": "m.csv", "quality": verdict.to_dict()}
    path = tmp_path / "identification.json"
    path.write_text(json.dumps(result_to_dict(result, notes)))
    back = read_identification(path)
    assert not hasattr(back, "identifiability")  # a record: the analysis is summarised
    assert back.identifiability_summary == result.identifiability_summary

    live = calibration_text(result, {"data": "m.csv", "quality": verdict})
    assert calibration_text(back) == live
    lines = live.splitlines()
    assert lines[0] == f"pincal calibration of {mech.name} (preset {params.label}, gauss-newton)"
    assert lines[1].startswith(f"data: m.csv ({result.residuals.shape[0]} poses")
    assert f"identifiable: {result.identifiability.rank} of {len(params)} parameters" in lines
    assert sum(line.startswith(tuple(result.identified_names)) for line in lines) == len(
        result.identified_names
    )
    assert any(line.startswith("noise (1σ, declared): ") for line in lines)
    assert lines[-1].startswith("quality gate:") or lines[-1].startswith("  ")
    if machine == "rrr3":  # the planar machine's blocks are named by their components
        assert "measured components x y rz" in lines[1]
        assert "position (x y) RMS" in live and "orientation (rz) RMS" in live


def test_outlier_advice_follows_the_loss():
    from pincal.report import quality_lines

    record = {"passed": True, "outlier_poses": [3], "outlier_limit": 3.0}
    assert quality_lines(record)[-1].endswith("consider --loss huber")
    robust = quality_lines(record, "huber")[-1]
    assert robust.endswith("down-weighted by the huber loss") and "consider" not in robust
