"""The independent compliant truths of scripts/studies/*_deflection.py against pincal.

The studies simulate compliant machines with their own statics (not pincal's term
model); these tests pin that statics to pincal's at the rigid level (forces, torques,
forward kinematics), check pincal's strut elongation against theirs, and measure where
the first-order substitute of its Jacobian columns departs from it.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from pincal.model import (
    actual_joint_values,
    joint_term_basis,
    strut_loads,
    undeflected_commands,
)
from tests.studies.scripts import load_script

hexa = load_script("hexaslide_deflection")
arm = load_script("arm_deflection")


def _hexaslide(seed: int, sag: float):
    mech = hexa.with_payload(hexa.load_mechanism(hexa.HEXASLIDE), hexa.PAYLOAD)
    params = hexa.with_joint_terms(mech, hexa.parameters(mech, "pus54"), ("strut-compliance",))
    comp = np.asarray(params.joint_terms)
    rng = np.random.default_rng(seed)
    truth = np.zeros(len(params))
    truth[:54] = rng.normal(0.0, 2e-4, 54)
    truth[comp] = -sag / 66.8 * rng.uniform(0.5, 1.5, comp.size)  # [m/N]
    rows = hexa.sample_actuators(mech, 6, rng)
    return mech, params, comp, truth, rows


def test_hexaslide_statics_equals_pincals_on_the_true_geometry():
    mech, params, comp, truth, rows = _hexaslide(3, 0.0)
    actual = params.apply(mech, truth)
    h = hexa.Hexaslide.of(actual)
    names = tuple(params.parameters[k].joint for k in comp)
    forces, _ = strut_loads(actual, rows, names)
    for q, f in zip(rows, forces, strict=True):
        t, R = h.pose(q, h.ell, *hexa.HOME)
        T = actual.forward(q)
        assert np.max(np.abs(T.translation - t)) < 1e-12
        assert np.max(np.abs(T.rotation - R)) < 1e-12
        assert np.max(np.abs(h.forces(q, t, R) - f)) < 1e-8 * np.max(np.abs(f))  # [N]


def _strut_model_error(sag: float) -> float:
    """RMS distance [m] of pincal's deflected hexaslide from the exact strut elongation."""
    mech, params, comp, truth, rows = _hexaslide(5, sag)
    actual = params.apply(mech, truth)
    h = hexa.Hexaslide.of(actual)
    joints = actual_joint_values(mech, params, truth, rows)
    err = [
        np.linalg.norm(actual.forward(qm).translation - h.deflected(q, truth[comp], *hexa.HOME)[0])
        for q, qm in zip(rows, joints, strict=True)
    ]
    return float(np.sqrt(np.mean(np.square(err))))


def test_strut_deflection_is_the_exact_elongation():
    """pincal lengthens the struts of its own machine: the study's independent statics
    to round-off at 10 µm, 0.5 mm and 1 mm of sag (the first-order substitute it used
    before missed by microns at 0.5–1 mm)."""
    for sag in (1e-5, 5e-4, 1e-3):
        assert _strut_model_error(sag) < 1e-10, sag  # [m]


def test_strut_commands_invert_the_deflection():
    mech, params, _, truth, rows = _hexaslide(7, 5e-4)
    actual = params.apply(mech, truth)
    joints = actual_joint_values(mech, params, truth, rows)
    assert np.max(np.abs(joints - rows)) > 1e-5  # the load moved the joints [m]
    back = undeflected_commands(actual, params, truth, joints)
    assert np.max(np.abs(back - rows)) < 1e-11  # [m]


def _first_order(actual, params, comp, truth, rows) -> np.ndarray:
    """Joint values (m, 6) of the columns' fixed point ``q = u + L(q) c`` [m]: the rigid
    substitute (nominal strut lengths, carriages moved) the Jacobian linearises."""
    sub, q = params.subset(comp), rows.copy()
    for _ in range(60):
        q = rows + joint_term_basis(actual, sub, q, {}) @ truth[comp]
    return q


def _substitute_force_error(sag: float) -> tuple[float, float, float]:
    """(largest relative strut-force error, its elongation error [m], substitute miss [m]).

    The strut forces of the columns' rigid substitute, at its own deflected
    configuration, against the elongated machine's (carriages at the command, struts
    lengthened) at the exact deflected pose.
    """
    mech, params, comp, truth, rows = _hexaslide(5, sag)
    actual = params.apply(mech, truth)
    h = hexa.Hexaslide.of(actual)
    names = tuple(params.parameters[k].joint for k in comp)
    joints = _first_order(actual, params, comp, truth, rows)
    rel, elong, miss = [], [], []
    for u, qm in zip(rows, joints, strict=True):
        t, R = h.deflected(u, truth[comp], *hexa.HOME)
        exact = h.forces(u, t, R)
        model = strut_loads(actual, qm[None], names)[0][0]
        rel.append(np.max(np.abs(model - exact)) / np.max(np.abs(exact)))
        elong.append(np.max(np.abs(truth[comp] * (model - exact))))
        miss.append(np.linalg.norm(actual.forward(qm).translation - t))
    return max(rel), max(elong), max(miss)


def test_first_order_columns_carry_the_substitute_geometrys_force():
    """The Jacobian's columns stay first order: at 0.5 mm of sag their substitute's strut
    directions differ from the elongated machine's (≈ 0.4 % in force), and the elongation
    that force error makes is the size of the substitute's pose error (same order) — the
    error pincal's deflection no longer makes, a column error of the same relative size."""
    rel_small, _, _ = _substitute_force_error(1e-5)
    rel, elong, miss = _substitute_force_error(5e-4)
    assert rel_small < 1e-4, rel_small
    assert rel > 1e-3, rel
    assert 1e-6 < miss and miss / 3 < elong < 3 * miss, (elong, miss)  # [m]


def test_arm_torques_equal_pinocchios_gravity():
    mech = arm.with_payload(arm.load_mechanism("ur5"), arm.TOOL)
    model, data = mech.model, mech.model.createData()
    for q in mech.configurations(arm.sample_actuators(mech, 5, np.random.default_rng(0))):
        expected = pin.computeGeneralizedGravity(model, data, q).copy()
        assert np.max(np.abs(arm.torques(model, data, q) - expected)) < 1e-10  # [N·m]
