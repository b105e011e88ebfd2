"""A simulated 6-D marker body table of a UR5, computed with Pinocchio alone.

The truth is built independently of pincal's parameterisation: the UR5 URDF is loaded
into Pinocchio, each joint placement is perturbed by a random SE(3) (±``perturb`` m and
rad per twist coordinate), and the body's pose is ``T_instrument_base · oMf(wrist_3_link)
· T_link_body`` with noise (position [m] per coordinate, rotation [rad] per axis of a
small rotation applied on the body side). Orientation columns are roll, pitch, yaw in
degrees (R = Rz(yaw)·Ry(pitch)·Rx(roll)).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin

from pincal.model import resolve_named

JOINTS = (
    "shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
    "wrist_1_joint", "wrist_2_joint", "wrist_3_joint",
)  # fmt: skip
T_INSTRUMENT_BASE = pin.SE3(pin.rpy.rpyToMatrix(0.2, 0.1, -0.5), np.array([0.8, 0.5, -0.2]))
T_LINK_BODY = pin.SE3(pin.rpy.rpyToMatrix(0.3, -0.2, 0.6), np.array([0.02, 0.04, 0.1]))


def body_poses(
    n: int,
    seed: int,
    sigma_p: float = 5e-5,
    sigma_r: float = 2e-4,
    perturb: float = 5e-4,
    truth_seed: int = 0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(q (n, 6) [rad], positions (n, 3) [m], rotations (n, 3, 3)) of the perturbed UR5."""
    model = pin.buildModelFromUrdf(str(resolve_named("ur5").urdf))
    rng_truth = np.random.default_rng(truth_seed)
    for j in range(1, model.njoints):
        twist = pin.Motion(rng_truth.uniform(-perturb, perturb, 6))
        model.jointPlacements[j] = model.jointPlacements[j] * pin.exp6(twist)
    data = model.createData()
    frame = model.getFrameId("wrist_3_link")
    rng = np.random.default_rng(seed)
    q = rng.uniform(-np.pi, np.pi, (n, 6))
    assert [model.names[i] for i in range(1, 7)] == list(JOINTS)
    P, R = np.empty((n, 3)), np.empty((n, 3, 3))
    for i, qi in enumerate(q):
        pin.framesForwardKinematics(model, data, qi)
        T = T_INSTRUMENT_BASE * data.oMf[frame] * T_LINK_BODY
        P[i] = T.translation + rng.normal(0, sigma_p, 3)
        R[i] = T.rotation @ pin.exp3(rng.normal(0, sigma_r, 3))
    return q, P, R


def write_body_table(path: Path, q: np.ndarray, P: np.ndarray, R: np.ndarray) -> Path:
    """A marker table: the joints [rad], x y z [mm], roll pitch yaw [deg]."""
    lines = [",".join([*JOINTS, "x", "y", "z", "roll", "pitch", "yaw"])]
    for qi, p, r in zip(q, P, R, strict=True):
        rpy = np.degrees(pin.rpy.matrixToRpy(r))
        lines.append(",".join(f"{v:.12g}" for v in (*qi, *(p * 1e3), *rpy)))
    path.write_text("\n".join(lines) + "\n")
    return path
