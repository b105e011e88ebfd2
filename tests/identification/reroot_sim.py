"""Marker positions of a humanoid chain measured from its sole, computed with Pinocchio alone.

The truth is Pinocchio's model of the *original* tree (root ``base_link``, the URDF
as shipped): every joint placement perturbed by a random SE(3) (±``perturb`` m and rad
per twist coordinate), and the marker is seen as ``T_instrument_sole · oMf(sole)⁻¹ ·
oMf(link) · p_marker`` — no re-rooted model and none of pincal's parameterisation.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from pincal.model import resolve_named

T_INSTRUMENT_ROOT = pin.SE3(pin.rpy.rpyToMatrix(0.1, -0.2, 0.4), np.array([0.6, -0.3, 0.1]))
MARKER = np.array([0.03, -0.02, 0.08])


def perturbed_model(robot: str, perturb: float, seed: int) -> pin.Model:
    """Pinocchio's model of ``robot``'s URDF, every joint placement displaced at random."""
    model = pin.buildModelFromUrdf(str(resolve_named(robot).urdf))
    rng = np.random.default_rng(seed)
    for j in range(1, model.njoints):
        twist = pin.Motion(rng.uniform(-perturb, perturb, 6))
        model.jointPlacements[j] = model.jointPlacements[j] * pin.exp6(twist)
    return model


def marker_points(model: pin.Model, root: str, link: str, names: tuple[str, ...],
                  q: np.ndarray, sigma: float, seed: int) -> np.ndarray:  # fmt: skip
    """(n, 3) marker positions [m] in the instrument frame, noise σ per coordinate.

    Args:
        model: the truth (:func:`perturbed_model`); root, link: the chain's two ends.
        names: the joints of the columns of ``q`` (n, len(names)) [rad, m]; every other
            joint at 0.
    """
    data = model.createData()
    rng = np.random.default_rng(seed)
    f_root, f_link = model.getFrameId(root), model.getFrameId(link)
    out = np.empty((len(q), 3))
    for i, qi in enumerate(q):
        full = pin.neutral(model)
        for name, v in zip(names, qi, strict=True):
            full[model.idx_qs[model.getJointId(name)]] = v
        pin.framesForwardKinematics(model, data, full)
        T = T_INSTRUMENT_ROOT * data.oMf[f_root].inverse() * data.oMf[f_link]
        out[i] = T.act(MARKER) + rng.normal(0, sigma, 3)
    return out
