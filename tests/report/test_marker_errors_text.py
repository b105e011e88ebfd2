"""`pincal validate --data`'s lines of further markers, rendered from typed errors."""

from __future__ import annotations

import numpy as np
import pytest

from pincal.report import marker_errors_text
from pincal.validation import MarkerErrors


def test_record_and_lines_in_mm():
    e = MarkerErrors(("x2", "y2", "z2"), np.array([3e-3, 4e-3]), np.array([1e-4, 2e-4]))
    doc = e.to_dict()
    assert doc["columns"] == ["x2", "y2", "z2"]
    assert doc["before_rms_position_mm"] == pytest.approx(np.sqrt(12.5))
    assert doc["after_max_position_mm"] == pytest.approx(0.2)
    text = marker_errors_text([e, MarkerErrors(("a", "b", "c"), np.ones(1), np.zeros(1))])
    first, second = text.splitlines()
    assert first == ("  marker x2 y2 z2: position RMS nominal 3.5355 mm, calibrated 0.1581 mm "
                     "(max 0.2000 mm); the table above: the first marker")  # fmt: skip
    assert second.startswith("  marker a b c: position RMS nominal 1000.0000 mm")
    assert text.endswith("\n") and marker_errors_text([]) == ""
