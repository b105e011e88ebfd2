"""Closed-form registration of markers: the instrument frame and the marker on its link.

:func:`register_markers` solves, before any identification, the two constant unknowns
of a marker calibration (:mod:`pincal.measure._markers`): with the marker fixed, the
robot base in the instrument frame is a best-fit rigid transform (Kabsch); with the
base fixed, the marker is linear least squares; the two alternate until the marker
moves less than 1 nm. A marker body's orientation on the link (orientation columns)
follows in closed form from the registered base: the rotation nearest the sum of
``(R_base·R_link,i)ᵀ·R_measured,i``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pincal.errors import MeasurementError, ModelFileError, UnidentifiableError
from pincal.measure._markers import marker_frame
from pincal.measure._measurements import Measurements
from pincal.measure._tracker import COLLINEAR_RTOL, RigidFit, fit_rigid_transform, kabsch
from pincal.model import BASE_JOINT, TOOL_JOINT, Mechanism, with_joint_origin

__all__ = ["MarkerRegistration", "register_markers"]


@dataclass(frozen=True)
class MarkerRegistration:
    """Closed-form registration of the instrument frame and the marker offset.

    Attributes:
        T_instrument_base: robot base in the instrument frame.
        marker: marker in the measured link's frame [m].
        fit: the final rigid fit (``fit.rms`` [m] is what identification starts from).
        iterations: alternations used.
        mechanism: the input mechanism with ``base_frame`` and ``tool_frame`` set (and
            ``marker<k>_frame`` of further markers).
        more_markers: further markers in the link's frame [m] (k = 2, 3, …).
        rotation: a marker body's orientation in the link's frame (3, 3), or None
            (positions only: the mechanism's ``tool_frame`` rotation kept).
        orientation_rms: RMS over the poses of the body's rotation error angle
            after the registration [rad], or None (positions only).
    """

    T_instrument_base: pin.SE3
    marker: np.ndarray
    fit: RigidFit
    iterations: int
    mechanism: Mechanism
    more_markers: tuple[np.ndarray, ...] = ()
    rotation: np.ndarray | None = None
    orientation_rms: float | None = None


def _project_rotation(M: np.ndarray) -> np.ndarray:
    """The rotation nearest ``M`` (3, 3) in the Frobenius norm (polar factor, det +1)."""
    U, _, Vt = np.linalg.svd(M)
    d = np.sign(np.linalg.det(U @ Vt)) or 1.0
    return U @ np.diag([1.0, 1.0, d]) @ Vt


def _body_rotation(T: pin.SE3, R_f: np.ndarray, R_meas: np.ndarray) -> tuple[np.ndarray, float]:
    """(rotation of the body on the link, RMS error angle [rad]) for a registered base.

    ``R_meas,i ≈ R_base · R_f,i · R_body``: R_body is the rotation nearest the sum of
    ``(R_base R_f,i)ᵀ R_meas,i`` (closed form, the chordal least-squares mean).
    """
    A = np.einsum("ij,mjk->mik", T.rotation, R_f)  # (m, 3, 3) link in the instrument
    R = _project_rotation(np.einsum("mji,mjk->ik", A, R_meas))
    angles = [np.linalg.norm(pin.log3((a @ R).T @ b)) for a, b in zip(A, R_meas, strict=True)]
    return R, float(np.sqrt(np.mean(np.square(angles))))


def _check_spread(mech: Mechanism, points: np.ndarray, q_act: np.ndarray) -> None:
    """Refuse nominal marker points (n, 3) [m] that are coincident or collinear.

    ``q_act`` (n, n_act) [rad, m]: rows of one joint reading are named as such.
    """
    centred = points - points.mean(axis=0)
    sv = np.linalg.svd(centred, compute_uv=False)
    if sv[0] > 0.0 and sv[1] > COLLINEAR_RTOL * sv[0]:
        return
    link = mech.tree.joints[TOOL_JOINT].parent
    if not np.ptp(q_act, axis=0).any():
        raise UnidentifiableError(
            f"the instrument frame cannot be registered: every row has the same joint "
            f"readings, so the nominal marker on link {link!r} never moves; measure poses "
            "that move the joints (check that the joint columns are the robot's readings)"
        )
    raise UnidentifiableError(
        f"the instrument frame cannot be registered: the nominal marker positions on link "
        f"{link!r} are coincident or collinear over the poses (moved by "
        f"{', '.join(mech.actuated)}); give the marker off the joint's axis (--marker X,Y,Z "
        "[mm]), --instrument-frame known, or a link further along the chain"
    )


def register_markers(
    mech: Mechanism,
    measurements: Measurements,
    marker_known: bool = False,
    frame_known: bool = False,
    max_iterations: int = 500,
    more: tuple[Measurements, ...] = (),
) -> MarkerRegistration:
    """Instrument frame and marker offset in closed form (alternating Kabsch / least squares).

    Args:
        mech: from :func:`marker_mechanism` (``base_frame`` and ``tool_frame`` joints).
        measurements: marker positions [m] in the instrument frame, ≥ 3 poses; with
            rotations (a marker body), the body's rotation on the link is registered too.
        marker_known: keep the mechanism's ``tool_frame`` translation.
        frame_known: keep the mechanism's ``base_frame``.
        max_iterations: alternation limit.
        more: positions of further markers, rows as ``measurements`` (their offsets
            are unknown, each on its ``marker<k>_frame`` joint's parent link; all
            markers share the rigid fit).

    Raises:
        MeasurementError: too few poses.
        UnidentifiableError: the nominal marker points are coincident or collinear (a
            marker on the axis of the one joint moving it): no frame registers them.
    """
    joints = [BASE_JOINT, TOOL_JOINT] + [marker_frame(k)[0] for k in range(1, len(more) + 1)]
    for j in joints:
        if j not in mech.tree.joints:
            raise ModelFileError(f"marker registration needs the {j!r} joint (marker_mechanism)")
    if len(measurements) < 3:
        raise MeasurementError(f"registration needs at least 3 poses, got {len(measurements)}")
    T_base = mech.tree.joints[BASE_JOINT].origin
    T_tool = mech.tree.joints[TOOL_JOINT].origin
    bare = with_joint_origin(
        with_joint_origin(mech, BASE_JOINT, pin.SE3.Identity()), TOOL_JOINT, pin.SE3.Identity()
    )
    qs = bare.configurations(measurements.q_act)
    # each marker's link (markers on several links: several chains) in the robot base
    links = [mech.tree.joints[TOOL_JOINT].parent]
    links += [mech.tree.joints[j].parent for j in joints[2:]]
    placed = {link: [bare.frame_placement(q, link) for q in qs] for link in set(links)}
    R_fs = [np.array([T.rotation for T in placed[link]]) for link in links]  # (m, 3, 3)
    t_fs = [np.array([T.translation for T in placed[link]]) for link in links]  # (m, 3)
    R_f = R_fs[0]
    P = [measurements.positions, *(m.positions for m in more)]
    mk = [np.asarray(T_tool.translation, dtype=float).copy()]
    mk += [np.zeros(3) for _ in more]

    def points() -> np.ndarray:  # every marker's nominal points, stacked
        return np.vstack([t + np.einsum("mij,j->mi", R, v)
                          for R, t, v in zip(R_fs, t_fs, mk, strict=True)])  # fmt: skip

    if not frame_known:
        _check_spread(mech, points(), measurements.q_act)
    T = T_base
    it = 0
    measured, ones = np.vstack(P), np.ones(sum(len(Pk) for Pk in P))
    while it < max_iterations:
        it += 1
        pred = points()
        if frame_known:
            T = T_base
        elif it == 1:  # checked once: shapes, NaN, collinear predicted points
            T = fit_rigid_transform(pred, measured).T
        else:  # the same closed form on the same (moved) points, unchecked
            T = pin.SE3(*kabsch(pred, measured, ones))
        moved = 0.0
        for k, Pk in enumerate(P):
            if k == 0 and marker_known:
                continue
            A = np.einsum("ij,mjk->mik", T.rotation, R_fs[k]).reshape(-1, 3)
            b = (Pk - t_fs[k] @ T.rotation.T - T.translation).reshape(-1)
            new = np.linalg.lstsq(A, b, rcond=None)[0]
            moved = max(moved, float(np.linalg.norm(new - mk[k])))
            mk[k] = new
        if moved < 1e-9 or frame_known or (marker_known and not more):
            break
    res = np.vstack(P) - (points() @ T.rotation.T + T.translation)  # every marker's rows
    dist = np.linalg.norm(res, axis=1)
    fit = RigidFit(T, res, dist, float(np.sqrt(np.mean(dist**2))))
    rotation, angle_rms = T_tool.rotation, None
    if measurements.rotations is not None:
        rotation, angle_rms = _body_rotation(T, R_f, measurements.rotations)
    out = with_joint_origin(mech, BASE_JOINT, T)
    out = with_joint_origin(out, TOOL_JOINT, pin.SE3(rotation, mk[0]))
    for k in range(1, len(mk)):
        out = with_joint_origin(out, marker_frame(k)[0], pin.SE3(np.eye(3), mk[k]))
    body = None if angle_rms is None else rotation
    return MarkerRegistration(T, mk[0], fit, it, out, tuple(mk[1:]), body, angle_rms)
