"""Mechanism.with_joint_origins (the one derivation) and ParameterSet.linearise.

``ParameterSet.apply`` and ``with_joint_origin`` both derive through
``Mechanism.with_joint_origins``; a linearisation is computed once per values and gives
the same mechanism and sensitivities as the values it was built from.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pincal
from pincal.errors import ParameterError, UnknownNameError
from pincal.model import Linearisation, with_joint_origin
from pincal.sensitivity import pose_sensitivity, sensitivities_batch

MACHINES = Path(__file__).parent / "machines"


@pytest.fixture(scope="module")
def rrr3():
    return pincal.load_mechanism(MACHINES / "rrr3")


def _origins(mech):
    return {j: uj.origin.homogeneous for j, uj in mech.tree.joints.items()}


def test_with_joint_origins_replaces_those_and_keeps_the_rest(rrr3):
    joint = next(j for j, uj in rrr3.tree.joints.items() if uj.movable)
    before = _origins(rrr3)
    T = rrr3.tree.joints[joint].origin * pin.SE3(np.eye(3), np.array([1e-3, -2e-3, 0.0]))
    moved = rrr3.with_joint_origins({joint: T})
    np.testing.assert_allclose(moved.tree.joints[joint].origin.homogeneous, T.homogeneous)
    after = _origins(moved)
    assert all(np.array_equal(after[j], before[j]) for j in before if j != joint)
    assert _origins(rrr3).keys() == before.keys()  # the input is not modified
    assert all(np.array_equal(_origins(rrr3)[j], before[j]) for j in before)
    assert (moved.name, moved.measured_frame, moved.actuated) == (
        rrr3.name,
        rrr3.measured_frame,
        rrr3.actuated,
    )
    assert moved.options == rrr3.options and moved.sidecar == rrr3.sidecar
    assert np.max(np.abs(moved.closure_residual(moved.q_home))) <= moved.options.tol
    assert moved.idle_branch == rrr3.idle_branch  # closed on home's assembly mode


def test_with_joint_origins_names_an_unknown_joint(rrr3):
    with pytest.raises(UnknownNameError, match="no_such_joint"):
        rrr3.with_joint_origins({"no_such_joint": pin.SE3.Identity()})


def test_apply_and_with_joint_origin_are_that_derivation(rrr3):
    params = pincal.parameters(rrr3, "full")
    values = np.random.default_rng(2).normal(0.0, 1e-3, len(params))
    applied = params.apply(rrr3, values)
    origins = {
        j: rrr3.tree.joints[j].origin * pin.exp6(v)
        for j, (_, v, _) in params.linearise(values).joint_twists.items()
    }
    derived = rrr3.with_joint_origins(origins)
    assert applied.urdf_xml == derived.urdf_xml
    np.testing.assert_array_equal(applied.q_home, derived.q_home)
    joint = params.joints[0]
    one = with_joint_origin(rrr3, joint, origins[joint])
    assert one.urdf_xml == rrr3.with_joint_origins({joint: origins[joint]}).urdf_xml


def test_linearisation_holds_the_exact_origin_derivatives(rrr3):
    params = pincal.parameters(rrr3, "full")
    values = np.random.default_rng(3).normal(0.0, 1e-2, len(params))
    lin = params.linearise(values)
    assert isinstance(lin, Linearisation) and lin.names == params.names
    np.testing.assert_array_equal(lin.values, values)
    assert not lin.values.flags.writeable
    assert params.linearise(lin) is lin  # passed on as it is
    for cols, v, eff in lin.joint_twists.values():
        Xi = np.stack([params.parameters[k].twist for k in cols], axis=1)
        np.testing.assert_allclose(v, Xi @ values[cols], rtol=0, atol=1e-15)
        # d/dδ of origin·exp6(Xi (values + δ)) in the displaced origin frame, by central FD
        h = 1e-6
        for c, k in enumerate(cols):
            e = np.zeros(len(params))
            e[k] = h
            plus, minus = (pin.exp6(Xi @ (values + s * e)[cols]) for s in (1, -1))
            fd = pin.log6(pin.exp6(v).inverse() * plus).vector
            fd -= pin.log6(pin.exp6(v).inverse() * minus).vector
            np.testing.assert_allclose(eff[:, c], fd / (2 * h), atol=1e-8)


def test_linearisation_of_another_set_is_refused(rrr3):
    full = pincal.parameters(rrr3, "full")
    sub = full.subset(range(3), "sub")
    with pytest.raises(ParameterError, match="linearise this set"):
        sub.apply(rrr3, full.linearise(None))


def test_a_linearisation_gives_what_its_values_give(rrr3):
    params = pincal.parameters(rrr3, "full")
    values = np.random.default_rng(5).normal(0.0, 1e-4, len(params))
    lin = params.linearise(values)
    at = params.apply(rrr3, lin)
    assert at.urdf_xml == params.apply(rrr3, values).urdf_xml
    rows = pincal.sample_actuators(at, 5, np.random.default_rng(0))
    qs, bk = at.configurations_batch(rows)
    a = sensitivities_batch(at, params, qs, bk, lin).jacobian
    b = sensitivities_batch(at, params, qs, bk, values).jacobian
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(
        pose_sensitivity(at, params, qs[0], lin).jacobian,
        pose_sensitivity(at, params, qs[0], values).jacobian,
    )
