"""The report's quality section says how the σ were made and, with estimated noise, the
Student-t / F intervals (calibration.json ``quality.uncertainty``)."""

from __future__ import annotations

from pincal.report._sections import quality_section


def _notes(uncertainty: dict) -> dict:
    return {"quality": {"passed": True, "uncertainty": uncertainty}}


def test_estimated_noise_intervals_are_written_in_the_quality_section() -> None:
    intervals = {"level": 0.95, "k": 42, "noise": "estimated", "dof": 12.8, "each_sigma": 2.163,
                 "joint_d2": 98.51, "approximate": True}  # fmt: skip
    section = quality_section(_notes({"linear": True, "directions_checked": 12,
                                      "intervals": intervals}))  # fmt: skip
    assert section is not None
    assert "Intervals: the noise is estimated on ν = 12.8" in section.text
    assert "±2.16σ (Student t)" in section.text and "d² ≤ 98.51 (k·F)" in section.text
    assert "approximate on so few degrees of freedom." in section.text
    assert "Uncertainties: linear over one σ along the 12 most uncertain" in section.text


def test_declared_noise_says_no_intervals() -> None:
    intervals = {"level": 0.95, "k": 42, "noise": "declared", "dof": None}
    section = quality_section(_notes({"linear": True, "directions_checked": 12,
                                      "intervals": intervals}))  # fmt: skip
    assert section is not None and "Student" not in section.text
