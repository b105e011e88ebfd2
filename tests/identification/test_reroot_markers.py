"""A humanoid's chain measured from its sole: the marker route on a re-rooted tree.

TALOS stands on its left sole, fixed to the capture system; the marker is on the left
arm's last link. The chain sole → leg → torso → arm (15 joints) is built by re-rooting
the URDF (:attr:`pincal.measure.MarkerSetup.root`); the truth is Pinocchio's model of
the URDF as shipped with every joint placement displaced (``reroot_sim``), none of
pincal's parameterisation. Before ``root`` the leg joints were locked at 0 as "off the
chain" and the fit could not follow their motion.
"""

from __future__ import annotations

import numpy as np
import pytest

from pincal.identification import fit_markers
from pincal.measure import MarkerSetup, Measurements, marker_mechanism
from pincal.model import sample_actuators
from tests.identification.reroot_sim import marker_points, perturbed_model

ROOT, LINK = "left_sole_link", "arm_left_7_link"


@pytest.fixture(scope="module")
def campaign():
    setup = MarkerSetup(LINK, root=ROOT)
    mech = marker_mechanism("talos", setup)
    q = sample_actuators(mech, 200, np.random.default_rng(1))
    return setup, mech, q, perturbed_model("talos", 1e-3, 0)


def _fit(campaign, sigma: float, n: int = 150):
    setup, mech, q, truth = campaign
    P = marker_points(truth, ROOT, LINK, mech.actuated, q, sigma, 2)
    meas = Measurements(q[:n], P[:n], None, ("x", "y", "z"), mech.measured_frame, mech.actuated)
    fit = fit_markers(mech, setup, meas)
    cal = fit.calibrated
    pred = np.array([cal.frame_placement(c).translation for c in cal.configurations(q[n:])])
    return fit, np.sqrt(np.mean(np.sum((pred - P[n:]) ** 2, axis=1)))


def test_rerooted_chain_has_the_leg_torso_and_arm(campaign):
    setup, mech, _, _ = campaign
    legs = [f"leg_left_{k}_joint" for k in range(6, 0, -1)]
    assert list(mech.actuated) == [*legs, "torso_1_joint", "torso_2_joint",
                                   *(f"arm_left_{k}_joint" for k in range(1, 8))]  # fmt: skip
    assert MarkerSetup.from_dict(setup.to_dict()) == setup


def test_exact_data_of_the_original_tree_are_reproduced(campaign):
    """No noise: the re-rooted chain's parameters span the original tree's errors exactly."""
    fit, held_out = _fit(campaign, 0.0)
    assert fit.result.success
    assert held_out < 1e-9  # [m], on 50 poses not fitted; the nominal chain is off by mm
    reg = fit.registration.mechanism
    _, mech, q, truth = campaign
    P = marker_points(truth, ROOT, LINK, mech.actuated, q[150:], 0.0, 2)
    nominal = np.array([reg.frame_placement(c).translation for c in reg.configurations(q[150:])])
    assert np.sqrt(np.mean(np.sum((nominal - P) ** 2, axis=1))) > 1e-3


def test_noisy_data_predict_at_the_noise_level(campaign):
    """σ 0.1 mm per coordinate: held-out error ≈ √3·σ (noise of the new points alone)."""
    sigma = 1e-4
    fit, held_out = _fit(campaign, sigma)
    assert fit.result.success
    assert 0.8 * np.sqrt(3) * sigma < held_out < 1.25 * np.sqrt(3) * sigma
