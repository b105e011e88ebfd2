"""Full calibration of the AACMM from probe positions (scripts/studies/aacmm_calibration.py)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import pincal
from pincal.model import dh_fk
from tests.studies.scripts import load_script

script = load_script("aacmm_calibration")
build = load_script("build_aacmm", "models")


def test_identifiability_names_the_five_position_blind_dh_errors():
    mech = pincal.load_mechanism("aacmm")
    ident = pincal.identifiability(mech, pincal.parameters(mech, "dh"))
    assert ident.rank == 23
    assert set(ident.unidentifiable_names) == set(script.UNIDENTIFIABLE)


def test_equivalent_truth_gives_the_same_probe_positions():
    """Independent check of the absorption formulas with numpy DH FK."""
    rows, errors = build.table1()
    names = {"joint_names": build.JOINT_NAMES, "link_names": build.LINK_NAMES}
    from pincal.model import (
        dh_errors_to_parameters,
        parameters_to_dh_errors,
    )

    values = dh_errors_to_parameters(errors, rows, **names)
    values["joint6_ax.tx"] = 2e-4  # make every absorbed error nonzero
    values["probe_joint_ax.tx"] = -5e-5
    eq = script.equivalent_truth(values)
    eq_full = {n: eq.get(n, 0.0) for n in values}
    errs, errs_eq = (parameters_to_dh_errors(v, rows, **names) for v in (values, eq_full))
    rng = np.random.default_rng(0)
    for q in rng.uniform(-np.pi, np.pi, (10, 6)):
        p = dh_fk(rows, q, errors=errs)[:3, 3]
        assert np.allclose(dh_fk(rows, q, errors=errs_eq)[:3, 3], p, atol=1e-12, rtol=0)
        assert np.linalg.norm(dh_fk(rows, q)[:3, 3] - p) > 1e-4


def test_noise_free_recovery_of_the_identifiable_errors():
    run = script.calibrate(n_poses=40, noise_mm=0.0, seed=1)
    assert len(run.result.params) == 23
    assert set(run.result.fixed) == set(script.UNIDENTIFIABLE)
    assert np.abs(run.error).max() <= 1e-9
    # Table 1 itself for the 20 untouched DH errors
    t1 = dict(
        zip(
            pincal.parameters(pincal.load_mechanism("aacmm"), "dh").names,
            script.table1_values(pincal.parameters(pincal.load_mechanism("aacmm"), "dh")),
            strict=True,
        )
    )
    untouched = [
        k
        for k, n in enumerate(run.result.params.names)
        if n not in ("joint6.offset", "joint6.tz", "probe_joint.tz")
    ]
    assert len(untouched) == 20
    for k in untouched:
        assert run.result.values[k] == pytest.approx(t1[run.result.params.names[k]], abs=1e-9)


def test_noisy_recovery_is_consistent_with_predicted_std():
    run = script.calibrate(n_poses=60, noise_mm=0.005, seed=4)
    r = run.result
    assert r.success
    assert 0.8 < r.reduced_chi2 < 1.25  # 180 − 23 degrees of freedom
    assert np.abs(run.z).max() < 4.0
    assert 0.4 < np.mean(run.z**2) < 2.0
    # residual at the noise level (3-D norm of 3 × 5 µm)
    assert r.after.rms_position == pytest.approx(np.sqrt(3) * 5e-6, rel=0.2)
    assert np.all(r.std < 1e-5)  # all std below 10 µm / 10 µrad


def test_registration_of_a_far_instrument_frame():
    T_true = pin.SE3(pin.exp3(np.array([0.1, -0.2, 0.4])), np.array([1.2, -0.4, 0.3]))
    run = script.registration(T_true, n_poses=40)
    # the rigid fit alone is close but biased by the arm's errors
    d0 = pin.log6(T_true.inverse() * run.T_registered).vector
    assert 1e-5 < np.linalg.norm(d0[:3]) < 2e-3
    # after identification the joint-1 axis frame in the instrument frame is exact
    d = pin.log6(run.T_joint1_true.inverse() * run.T_joint1_identified).vector
    assert np.abs(d).max() < 1e-9
    assert set(run.result.fixed) == set(script.UNIDENTIFIABLE) | {"base_frame.tz", "base_frame.rz"}
    assert run.result.after.max_position < 1e-9
