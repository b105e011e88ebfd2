"""The Cramér–Rao summary never mixes units in one figure (lengths mm, angles mrad)."""

from __future__ import annotations

import numpy as np

from pincal.design import CramerRaoReport


def _report(units, std):
    std = np.asarray(std, dtype=float)
    names = tuple(f"p{i}" for i in range(std.size))
    return CramerRaoReport(names, tuple(units), np.diag(std**2), std, np.nan, np.nan, 30, std.size)


def test_lengths_and_angles_are_summarised_apart():
    line = _report(("m", "m", "rad"), (1e-5, 3e-5, 2.4e-3)).summary()
    assert "lengths 0.02236 mm (max 0.03)" in line
    assert "angles 2.4 mrad (max 2.4)" in line
    assert "mm (max 2.4" not in line  # the former mixed figure: mrad shown as mm
    other = _report(("m", "1/K"), (1e-5, 2e-6)).summary()
    assert "1 other terms (largest p1: 2e-06 1/K)" in other
