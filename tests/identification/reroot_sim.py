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
                  q: np.ndarray, sigma: float, seed: int,
                  marker: np.ndarray = MARKER) -> np.ndarray:  # fmt: skip
    """(n, 3) marker positions [m] in the instrument frame, noise σ per coordinate.

    Args:
        model: the truth (:func:`perturbed_model`); root, link: the chain's two ends.
        names: the joints of the columns of ``q`` (n, len(names)) [rad, m]; every other
            joint at 0.
        marker: the marker in ``link``'s frame [m].
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
        out[i] = T.act(marker) + rng.normal(0, sigma, 3)
    return out


def _relative(model: pin.Model, data: pin.Data, root: int, face: int, full: np.ndarray) -> pin.SE3:
    pin.framesForwardKinematics(model, data, full)
    return data.oMf[root].inverse() * data.oMf[face]


def flush_poses(model: pin.Model, root: str, link: str, T_link_face: pin.SE3,
                names: tuple[str, ...], q_start: np.ndarray, axis: np.ndarray,
                normal: np.ndarray, offset: float, std: tuple[float, float],
                seed: int, within_limits: bool = True) -> np.ndarray:  # fmt: skip
    """Joint values (k, len(names)) at which the face touches the plane, from Pinocchio alone.

    Each start of ``q_start`` is moved by damped Gauss–Newton (finite-difference
    Jacobian of the truth model) until the face frame ``oMf(root)⁻¹ · oMf(link) ·
    T_link_face`` has ``normal·p − offset = ε_h`` and its axis ``R·axis`` tilted off
    ``normal`` by ``(ε_1, ε_2)`` (drawn with σ ``std`` = (height [m], tilt [rad]); tilts
    along the basis of :func:`pincal.measure._flush_contact.plane_basis` of ``normal``),
    so the flush residuals at the truth are exactly ``−ε``. Starts that do not converge
    (or, with ``within_limits``, end outside the joint limits) are dropped.
    """
    from pincal.measure._flush_contact import plane_basis

    data = model.createData()
    f_root, f_link = model.getFrameId(root), model.getFrameId(link)
    idx = [model.idx_qs[model.getJointId(n)] for n in names]
    lo, hi = model.lowerPositionLimit[idx], model.upperPositionLimit[idx]
    E = np.vstack(plane_basis(normal))
    rng = np.random.default_rng(seed)
    out = []
    for q0 in q_start:
        eps = np.array([rng.normal(0, std[0]), *rng.normal(0, std[1], 2)])

        def g(q: np.ndarray, eps: np.ndarray = eps) -> np.ndarray:
            full = pin.neutral(model)
            full[idx] = q
            T = _relative(model, data, f_root, f_link, full) * T_link_face
            return np.concatenate([[normal @ T.translation - offset],
                                   E @ (T.rotation @ axis)]) - eps  # fmt: skip

        q = np.array(q0, dtype=float)
        for _ in range(60):
            r = g(q)
            if np.abs(r).max() < 1e-13:
                break
            J = np.column_stack([(g(q + h) - r) / 1e-7 for h in np.eye(len(q)) * 1e-7])
            q = q - J.T @ np.linalg.solve(J @ J.T + 1e-9 * np.eye(3), r)
        if np.abs(g(q)).max() < 1e-12 and (not within_limits or np.all((q >= lo) & (q <= hi))):
            out.append(q)
    return np.array(out)
