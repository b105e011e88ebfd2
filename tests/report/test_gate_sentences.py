"""The report's quality section says what judged the fit: held-out figures, the probes."""

from __future__ import annotations

from pincal.report._gate_text import gate_sentences

PROBE = {"name": "drift", "explained": 0.11, "p_value": 0.048, "size": "a drift of 5.8 mm"}


def test_held_out_and_probes_are_said_largest_first():
    held = {
        "folds": 5,
        "calibrated": {"held_out_rms_mm": 4.182},
        "baseline": {"name": "registration only", "held_out_rms_mm": 4.785},
        "gain_mse_mm2": 5.41,
        "gain_standard_error_mm2": 2.4,
    }
    small = {**PROBE, "explained": 0.02, "size": "a scale"}
    lines = gate_sentences({"held_out": held, "probes": [small, PROBE]}, top=1)
    assert lines[0].startswith("Held-out prediction (5-fold")
    assert "4.182 mm calibrated against 4.785 mm for the registration only" in lines[0]
    assert "5.41 ± 2.4 mm²" in lines[0]
    assert "diagnostics, not refusals" in lines[1] and "a drift of 5.8 mm explains 11%" in lines[1]
    assert "a scale" not in lines[1] and "1 more in calibration.json" in lines[1]


def test_without_held_out_the_probes_are_the_gate():
    (line,) = gate_sentences({"probes": [PROBE], "held_out": None})
    assert "each refuses past its threshold" in line
    assert gate_sentences({}) == []
