"""Identifiability notes in amounts a user can picture (mm, mrad), not bare coefficients."""

from __future__ import annotations

import numpy as np

from pincal.sensitivity import analyse_jacobian


def test_a_dependent_column_is_said_in_mm_and_mrad():
    rng = np.random.default_rng(0)
    v, w = rng.normal(size=12), rng.normal(size=12)
    J = np.column_stack([v, w, 0.5 * v - 2.0 * w])  # c = 0.5·a − 2·b, in SI units
    ident = analyse_jacobian(J, ("a", "b", "c"), units=("m", "rad", "rad"))
    (line,) = ident.describe()
    # 1 mrad of c = 0.5 mrad·(m/rad) of a = 0.5 mm; and −2 mrad of b
    assert line == ("c is not identifiable: 1 mrad of it moves the measurements as "
                    "-2 mrad of b, +0.5 mm of a do")  # fmt: skip
    bare = analyse_jacobian(J, ("a", "b", "c"))
    assert bare.describe() == ["c is not identifiable (absorbed by -2.000·b +0.500·a)"]
    other = analyse_jacobian(J, ("a", "b", "c"), units=("m", "1/K", "rad"))
    assert "-0.002 1/K of b" in other.describe()[0]  # 1 mrad of c = −2·1e-3 K⁻¹ of b
