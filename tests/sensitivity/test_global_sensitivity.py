"""Global sensitivity (seed 002) against the closed-form wedge reference."""

from __future__ import annotations

import numpy as np
import pytest

import pincal
from pincal.errors import ParameterError
from pincal.machines import (
    PATENT_ERROR_NAMES,
    WedgeGeometry,
    wedge_error_matrix,
    wedge_global_sensitivity,
    wedge_inverse,
    wedge_patent_error_matrix,
    wedge_workspace_grid,
)
from pincal.sensitivity import (
    global_sensitivity,
    global_sensitivity_from_jacobians,
)

BOX = ((-0.05, 0.05), (-0.002, 0.002), (-0.01, 0.01))


@pytest.fixture(scope="module")
def wedge():
    mech = pincal.load_mechanism("wedge3")
    return mech, pincal.parameters(mech, "patent")


def _preset_columns(J7: np.ndarray, geom: WedgeGeometry) -> np.ndarray:
    """Map d(x, z, α)/d(l1, l2, k1, k2, dq0, dq1, dq2) onto the `patent` preset columns
    (mapping of models/wedge3/README.md)."""
    l1, l2, k1, k2, d0, d1, d2 = range(7)
    cols = [
        J7[..., d0],
        J7[..., d1],
        J7[..., d2],
        -J7[..., l1] - J7[..., d1],  # bar_end1_frame.tx = −δl1, dq1 = q1.offset + δl1
        J7[..., l2] - J7[..., d2],  # bar_end2_frame.tx = +δl2, dq2 = q2.offset − δl2
        (1 + geom.k1**2) * J7[..., k1],
        -(1 + geom.k2**2) * J7[..., k2],
    ]
    return np.stack(cols, axis=-1)


def test_matches_closed_form_reference(wedge) -> None:
    mech, params = wedge
    geom = WedgeGeometry.nominal()
    q = wedge_inverse(wedge_workspace_grid(*BOX, n=4), geom)
    gs = global_sensitivity(mech, params, q)
    J = _preset_columns(wedge_error_matrix(q, geom), geom)  # (m, 3, 7)
    np.testing.assert_allclose(gs.position, np.linalg.norm(J[:, :2], axis=1).mean(0), rtol=1e-7)
    np.testing.assert_allclose(gs.orientation, np.abs(J[:, 2]).mean(0), rtol=1e-7)
    # the parameters that map 1:1 agree with the reference index itself
    ref = wedge_global_sensitivity(geom, wedge_workspace_grid(*BOX, n=4), columns="parameters")
    np.testing.assert_allclose(gs.position[:3], ref.position[4:], rtol=1e-7)
    np.testing.assert_allclose(gs.orientation[:3], ref.orientation[4:], rtol=1e-7)
    assert gs.position_normalised.max() == 1.0 and gs.orientation_normalised.max() == 1.0


def test_groups_of_the_symmetric_machine(wedge) -> None:
    mech, params = wedge
    q = wedge_inverse(wedge_workspace_grid(*BOX, n=4), WedgeGeometry.nominal())
    gs = global_sensitivity(mech, params, q)
    assert set(gs.groups) == {
        ("q1.offset", "q2.offset"),
        ("bar_end1_frame.tx", "bar_end2_frame.tx"),
        ("wedge1_slide.ry", "wedge2_slide.ry"),
    }
    assert gs.group_of("q0.offset") == ("q0.offset",)
    assert gs.insensitive == ()


def test_patent_columns_groups() -> None:
    """On the patent's 12 δd columns: 5 = 9 (= 6 = 10), 7 = 11, 8 = 12, entries 2-4 zero;
    entry 1 (δq0 in x = q0) stands alone."""
    geom = WedgeGeometry.nominal()
    q = wedge_inverse(wedge_workspace_grid(*BOX, n=4), geom)
    gs = global_sensitivity_from_jacobians(
        wedge_patent_error_matrix(q, geom), PATENT_ERROR_NAMES, [0, 1], [2]
    )
    assert set(gs.groups) == {
        ("f1.dq0", "f1.dq1", "f2.dq0", "f2.dq2"),
        ("f1.l1", "f2.l2"),
        ("f1.k1", "f2.k2"),
    }
    assert gs.insensitive == ("f0.zero2", "f0.zero3", "f0.zero4")


def test_groups_break_for_an_asymmetric_machine(wedge) -> None:
    mech, params = wedge
    values = np.zeros(len(params))
    values[params.index("bar_end2_frame.tx")] = 0.01  # l2 = 110 mm ≠ l1
    geom = WedgeGeometry(l1=0.1, l2=0.11, k1=0.2, k2=0.2)
    q = wedge_inverse(wedge_workspace_grid(*BOX, n=3), geom)
    gs = global_sensitivity(params.apply(mech, values), params, q)
    assert ("bar_end1_frame.tx", "bar_end2_frame.tx") not in gs.groups
    assert ("wedge1_slide.ry", "wedge2_slide.ry") not in gs.groups


def test_pkm5_insensitive_hinges_and_random_samples() -> None:
    mech = pincal.load_mechanism("pkm5")
    params = pincal.parameters(mech, "hinges24")
    gs = global_sensitivity(mech, params, 6, rng=1)
    assert set(gs.insensitive) == {"T3.tx", "T4.tx", "S3.tx", "S4.tx"}
    assert gs.n_samples == 6


def test_bad_input(wedge) -> None:
    mech, params = wedge
    with pytest.raises(ParameterError, match="shape"):
        global_sensitivity(mech, params, np.zeros((3, 2)))
    with pytest.raises(ParameterError, match="shape"):
        global_sensitivity_from_jacobians(np.zeros((2, 3, 4)), ["a"], [0], [1])
