"""A simulated campaign from Python, as ``pincal simulate`` runs it.

The errors are drawn within their bounds and only on parameters a built machine can
have; with no error seed the actual machine is the nominal one and its noise-free
poses are the nominal model's; the truth document lists what was drawn.
"""

from __future__ import annotations

import numpy as np

from pincal.model import load_mechanism, sample_actuators
from pincal.sensitivity import parameters
from pincal.workflow import buildable_mask, reachable_rows, simulate_campaign


def test_errors_are_drawn_within_their_bounds_on_buildable_parameters():
    mech = load_mechanism("stewart_6ups")  # 18 of its 204 parameters split a ball joint
    preset = "full"
    lines: list[str] = []
    run = simulate_campaign(mech, preset, None, 8, error_seed=3, error_size=(2.0, 20.0),
                            noise=(0.01, 0.1), seed=1, say=lines.append)  # fmt: skip
    params = parameters(mech, preset)
    bound = np.array([2e-3 if u == "m" else 20e-3 for u in params.units])
    assert run.names == tuple(params.names)
    assert np.all(np.abs(run.values) <= bound)
    assert np.any(run.values != 0.0)
    assert len(run.data) + len(run.skipped) == 8
    mask = buildable_mask(mech, params, sample_actuators(mech, 8, np.random.default_rng(1)))
    assert np.any(mask == 0.0) and np.all(run.values[mask == 0.0] == 0.0)
    assert lines[0] == "… sampling 8 random poses"
    doc = run.truth("pincal test", "seed:3")
    assert list(doc)[:5] == ["written_by", "model", "preset", "errors", "error_size_mm_mrad"]
    assert [p["value"] for p in doc["parameters"]] == [float(v) for v in run.values]
    assert doc["skipped_rows"] == run.skipped


def test_without_errors_the_actual_machine_is_the_nominal_one():
    mech = load_mechanism("wedge3")
    run = simulate_campaign(mech, "full", None, 5, error_seed=None, error_size=(1.0, 10.0),
                            noise=(0.0, 0.0), seed=2)  # fmt: skip
    assert not np.any(run.values)
    data = run.data
    for q, p in zip(data.q_act, data.positions, strict=True):  # type: ignore[union-attr]
        np.testing.assert_allclose(p, mech.forward(q).translation, atol=1e-9)
    rows, skipped = reachable_rows(mech, data.q_act)  # type: ignore[union-attr]
    assert skipped == [] and len(rows) == 5
