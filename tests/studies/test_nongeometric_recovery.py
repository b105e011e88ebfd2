"""scripts/studies/nongeometric_recovery.py: joint terms recovered at the CRB (fast)."""

from __future__ import annotations

import numpy as np
import pytest

from tests.studies.scripts import load_script

script = load_script("nongeometric_recovery")


@pytest.mark.slow  # ~40 s; joint terms recovered fast: tests/identification/test_model_selection
def test_joint_terms_recovered_at_the_bound():
    """12 seeded UR5 calibrations with compliance, gain and harmonics on every joint.

    With a known σ, the Mahalanobis error / n of one draw is χ²_n / n (sd √(2/n));
    the mean over 12 draws of n ≈ 63 has an sd ≈ 0.05, that of the ≈ 33 joint terms
    ≈ 0.07. A wrong Jacobian column, a biased estimate or a dishonest covariance
    moves the mean far out of the accepted band (4 sd).
    """
    out = script.study(12, 60, seed=7, terms=("compliance", "gain", "harmonics"))
    assert out[0].n_terms >= 30  # 3 compliances (the gravity-loaded joints), 6 gains, 24 harmonics
    maha = np.mean([d.maha for d in out])
    maha_terms = np.mean([d.maha_terms for d in out])
    sd = np.sqrt(2 / out[0].n / len(out))
    sd_terms = np.sqrt(2 / out[0].n_terms / len(out))
    assert abs(maha - 1) < 4 * sd, maha
    assert abs(maha_terms - 1) < 4 * sd_terms, maha_terms


@pytest.mark.slow
def test_leg_compliance_under_a_payload_recovered_at_the_bound():
    """10 seeded Stewart calibrations: 42 geometric parameters and six legs' axial
    compliance under a 20 kg payload (the loop-closure equilibrium's leg forces)."""
    out = script.study(10, 60, seed=3, terms=("compliance",), robot="stewart")
    assert out[0].n == 48 and out[0].n_terms == 6
    maha = np.mean([d.maha for d in out])
    maha_terms = np.mean([d.maha_terms for d in out])
    assert abs(maha - 1) < 4 * np.sqrt(2 / 48 / len(out)), maha
    assert abs(maha_terms - 1) < 4 * np.sqrt(2 / 6 / len(out)), maha_terms


@pytest.mark.parametrize(("robot", "n", "n_terms"), [("ur5", 35, 5), ("stewart", 48, 6)])
def test_thermal_coefficients_recovered_at_the_bound(robot, n, n_terms):
    """10 seeded calibrations at 18–28 °C: the arm's link lengths (wrist_2's absorbed by
    shoulder_lift's) and the Stewart platform's leg strokes expanding with temperature."""
    out = script.study(10, 60, seed=5, terms=("temperature",), robot=robot)
    assert out[0].n == n and out[0].n_terms == n_terms
    maha = np.mean([d.maha for d in out])
    maha_terms = np.mean([d.maha_terms for d in out])
    assert abs(maha - 1) < 4 * np.sqrt(2 / n / len(out)), maha
    assert abs(maha_terms - 1) < 4 * np.sqrt(2 / n_terms / len(out)), maha_terms


@pytest.mark.slow
def test_strut_compliance_under_a_payload_recovered_at_the_bound():
    """10 seeded hexaslide calibrations: 54 geometric parameters and six struts' axial
    compliance under a 20 kg payload, the struts lengthened pose by pose (physical
    model) while the fit models the elongation as joint changes."""
    out = script.study(10, 60, seed=3, terms=("strut-compliance",), robot="hexaslide")
    assert out[0].n == 60 and out[0].n_terms == 6
    maha = np.mean([d.maha for d in out])
    maha_terms = np.mean([d.maha_terms for d in out])
    assert abs(maha - 1) < 4 * np.sqrt(2 / 60 / len(out)), maha
    assert abs(maha_terms - 1) < 4 * np.sqrt(2 / 6 / len(out)), maha_terms
