"""A 6-D marker body calibrated with its orientation: recovery at the level of its covariance.

The table is simulated with Pinocchio alone (:mod:`tests.identification.marker_body_sim`:
perturbed UR5 joint placements, an instrument frame and a body pose on the link,
roll-pitch-yaw in degrees), read by the marker reader and fitted by ``fit_markers``.
The truth in the fit's own coordinates is the fit of the same poses without noise from
the same registered start (it reproduces the table to 1e-9 m / rad: the model spans the
perturbation); the fitted parameters scatter about it as their covariance says
(Mahalanobis d²/k near 1 over draws, k ≈ 30).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from pincal.identification import fit_markers, identify
from pincal.io import read_marker_data
from pincal.measure import MarkerSetup, marker_mechanism, register_markers
from pincal.sensitivity import parameters
from tests.identification.marker_body_sim import T_LINK_BODY, body_poses, write_body_table

SETUP = MarkerSetup("wrist_3_link", length_unit="mm", orientation_columns=("roll", "pitch", "yaw"),
                    orientation="rpy-deg")  # fmt: skip
SIGMA_P, SIGMA_R = 5e-5, 2e-4  # [m], [rad]


@pytest.fixture(scope="module")
def mech():
    return marker_mechanism("ur5", SETUP)


def _read(tmp: Path, mech, seed: int, sp: float, sr: float):
    q, P, R = body_poses(40, seed, sp, sr)
    path = write_body_table(tmp / f"body_{seed}_{sp:g}.csv", q, P, R)
    return read_marker_data(path, mech, SETUP).sets


def test_the_table_is_read_as_poses_and_the_registration_starts_the_orientation(tmp_path, mech):
    (meas,) = _read(tmp_path, mech, 1, 0.0, 0.0)
    assert meas.components == ("x", "y", "z", "rx", "ry", "rz")
    assert meas.rotations is not None and meas.rotations.shape == (40, 3, 3)
    reg = register_markers(mech, meas)
    assert reg.rotation is not None and reg.orientation_rms is not None
    # the body's rotation on the link within the robot's (1 mrad-level) errors
    err = np.linalg.norm(pin.log3(reg.rotation.T @ T_LINK_BODY.rotation))
    assert err < 5e-3
    assert reg.orientation_rms < 5e-3
    # without the orientation the body's rotation is left at identity: 0.7 rad away
    bare = register_markers(mech, _position_only(meas))
    assert bare.rotation is None and bare.orientation_rms is None


def _position_only(meas):
    from pincal.measure import Measurements

    return Measurements(meas.q_act, meas.positions, None, ("x", "y", "z"), meas.frame,
                        meas.actuated)  # fmt: skip


def test_noise_free_table_is_reproduced(tmp_path, mech):
    fit = fit_markers(mech, SETUP, _read(tmp_path, mech, 1, 0.0, 0.0))
    assert fit.result.after.rms_position < 1e-9
    assert fit.result.after.rms_orientation < 1e-9
    identified = set(fit.result.identified_names)
    assert {"tool_frame.rx", "tool_frame.ry", "base_frame.rz"} <= identified


def test_parameters_recovered_to_the_level_of_their_covariance(tmp_path, mech):
    ratios, sigmas = [], []
    for seed in range(2, 12):
        fit = fit_markers(mech, SETUP, _read(tmp_path, mech, seed, SIGMA_P, SIGMA_R))
        r = fit.result
        assert r.weighting is not None and r.weighting.source == "estimated"
        sigmas.append((r.weighting.position_std, r.weighting.orientation_std))
        start = fit.registration.mechanism
        (exact_meas,) = _read(tmp_path, mech, seed, 0.0, 0.0)  # same poses, no noise
        exact = identify(start, parameters(start, "chain"), exact_meas, "gauss-newton",
                         fit=list(r.identified_names),
                         noise={"position": 0.05, "orientation": 0.2})  # fmt: skip
        assert exact.after.rms_position < 1e-9 and exact.after.rms_orientation < 1e-9
        dx = (r.full_values - exact.full_values)[r.identified]
        ratios.append(dx @ np.linalg.solve(r.covariance, dx) / dx.size)
    # 10 draws of d²/k with k = 30: the mean within ±4 standard errors (≈ 0.08) of 1
    assert 0.68 < np.mean(ratios) < 1.32, ratios
    sp, sr = np.median(sigmas, axis=0)
    assert 0.8 < sp / SIGMA_P < 1.2 and 0.8 < sr / SIGMA_R < 1.2  # each block's own σ
