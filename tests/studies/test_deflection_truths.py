"""The independent compliant truths of scripts/studies/*_deflection.py against pincal.

The studies simulate compliant machines with their own statics (not pincal's term
model); these tests pin that statics to pincal's at the rigid level (forces, torques,
forward kinematics) and measure where pincal's first-order strut model departs from
the exact strut elongation.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from pincal.model import actual_joint_values, strut_loads
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


def test_strut_model_matches_the_exact_elongation_only_while_it_is_small():
    """pincal models a strut's elongation by the joint change that moves the platform as
    it does (first order): exact to 1e-3 µm at 10 µm of sag, microns at 0.5–1 mm."""
    small, large = _strut_model_error(1e-5), _strut_model_error(1e-3)
    assert small < 1e-8, small  # [m]
    assert large > 1e-6, large  # the second-order error of the joint-change form


def _substitute_force_error(sag: float) -> tuple[float, float, float]:
    """(largest relative strut-force error, its elongation error [m], model error [m]).

    pincal's strut term deflects a rigid substitute (nominal strut lengths, carriages
    moved); its strut forces at that configuration against the elongated machine's
    (carriages at the command, struts lengthened) at the exact deflected pose.
    """
    mech, params, comp, truth, rows = _hexaslide(5, sag)
    actual = params.apply(mech, truth)
    h = hexa.Hexaslide.of(actual)
    names = tuple(params.parameters[k].joint for k in comp)
    joints = actual_joint_values(mech, params, truth, rows)
    rel, elong, miss = [], [], []
    for u, qm in zip(rows, joints, strict=True):
        t, R = h.deflected(u, truth[comp], *hexa.HOME)
        exact = h.forces(u, t, R)
        model = strut_loads(actual, qm[None], names)[0][0]
        rel.append(np.max(np.abs(model - exact)) / np.max(np.abs(exact)))
        elong.append(np.max(np.abs(truth[comp] * (model - exact))))
        miss.append(np.linalg.norm(actual.forward(qm).translation - t))
    return max(rel), max(elong), max(miss)


def test_strut_model_error_is_the_substitute_geometrys_force():
    """The strut model's error at 0.5 mm of sag is the force of the rigid substitute: its
    strut directions differ from the elongated machine's (≈ 0.4 % in force), and the
    elongation that force error makes is the size of the pose error (same order)."""
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
