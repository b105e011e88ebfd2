"""A calibration directory with an identification and report notes, for report tests."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

import pincal
from pincal.identification import identify, result_to_dict


def identified_directory(tmp_path_factory, stewart, stewart42, stewart_poses, seed: int) -> Path:
    """Identify a simulated Stewart (errors and noise from ``seed``) and write its JSON."""
    rng = np.random.default_rng(seed)
    truth = rng.normal(0.0, 3e-4, len(stewart42))
    noise = pincal.NoiseModel(0.01, 0.02)
    meas = pincal.simulate_measurements(stewart42.apply(stewart, truth), stewart_poses, noise, rng)
    res = identify(stewart, stewart42, meas)
    out = tmp_path_factory.mktemp("cal")
    notes = {
        "truth": dict(zip(stewart42.names, truth, strict=True)),
        "validation_before": {"rms_position_mm": 1.2, "max_position_mm": 2.0},
        "validation_after": {"rms_position_mm": 0.01, "max_position_mm": 0.02},
        "validation_errors": {
            "before": {"position": list(rng.uniform(1e-3, 2e-3, 12))},
            "after": {"position": list(rng.uniform(1e-6, 2e-5, 12))},
        },
        "index_history": {"O1": [1.0, 2.0, 2.5]},
    }
    (out / "identification.json").write_text(json.dumps(result_to_dict(res, notes)))
    return out
