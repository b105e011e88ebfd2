"""The joint-kind hint of a mobility error: revolutes that should be spherical.

A new user's Delta often has plain revolute joints where its rods need ball ends: the
point (``3d``) closures then over-constrain the loops and the mobility comes out below
the number of actuators. :func:`spherical_hint` names every passive revolute joint on
the loops of the point closures and, when turning all of them into spherical joints
(three rotations about the same joint origin) gives a mobility equal to the number of
actuators at the given configuration, returns the sidecar text that declares them
spherical (``joint_name``/``joint_type``, see :mod:`pincal.model.files._sidecar`).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from pincal.model.loops._jacobian_shape import six_by_nv
from pincal.model.loops._kinematics import KinematicQueries

__all__ = ["open_loop_hint", "spherical_hint"]


def _rank(J: np.ndarray, rcond: float) -> int:
    if J.size == 0:
        return 0
    s = np.linalg.svd(J, compute_uv=False)
    return int(np.sum(s > rcond * s[0])) if s[0] > 0 else 0


def _loop_revolutes(queries: KinematicQueries) -> list[int]:
    """Passive 1-dof revolute joints (Pinocchio ids) on the loops of the point closures."""
    model, actuated = queries.model, set(queries.actuated)
    found: dict[int, None] = {}
    for (fa, fb), c in zip(queries.closure_fids, queries.closures, strict=True):
        if not c.is_point:
            continue
        sa = set(model.supports[model.frames[fa].parentJoint])
        sb = set(model.supports[model.frames[fb].parentJoint])
        for j in sorted(sa ^ sb):
            revolute = model.joints[j].shortname().startswith("JointModelR")  # RX…RUBZ too
            if model.nvs[j] == 1 and revolute and model.names[j] not in actuated:
                found[j] = None
    return list(found)


def _twist(data: pin.Data, model: pin.Model, f: int, j: int, e: np.ndarray) -> np.ndarray:
    """(6,) local twist of frame ``f`` per unit rotation about world axis ``e`` at joint ``j``.

    Zero when ``f`` is not in the joint's subtree.
    """
    if j not in model.supports[model.frames[f].parentJoint]:
        return np.zeros(6)
    M = data.oMf[f]
    v = np.cross(e, M.translation - data.oMi[j].translation)
    return np.concatenate([M.rotation.T @ v, M.rotation.T @ e])


def _extra_columns(
    queries: KinematicQueries, data: pin.Data, joints: list[int]
) -> tuple[np.ndarray, np.ndarray]:
    """Closure rows (n_closure_rows, 3·k) and measured-frame twists (6, 3·k) of new rotations.

    One column per rotation about world x, y, z at each joint's origin, moving the
    joint's subtree (what a spherical joint there would add).
    """
    model, measured = queries.model, queries.frame_id(queries.measured_frame)
    cols, twists = [], []
    for j in joints:
        for e in np.eye(3):
            rows = [
                c.jacobian(
                    data.oMf[fa],
                    data.oMf[fb],
                    _twist(data, model, fa, j, e)[:, None],
                    _twist(data, model, fb, j, e)[:, None],
                )[:, 0]
                for (fa, fb), c in zip(queries.closure_fids, queries.closures, strict=True)
            ]
            cols.append(np.concatenate(rows))
            twists.append(_twist(data, model, measured, j, e))
    return np.array(cols).T, np.array(twists).T


def spherical_hint(queries: KinematicQueries, q: np.ndarray, rcond: float) -> str:
    """A sentence for a mobility error at configuration ``q`` (nq,), or ``""``.

    Non-empty when the mechanism has point closures whose loops hold passive revolute
    joints and declaring every one of them spherical gives the mobility the actuated
    joints need (nv − closure rank − idle passive motions, ranks by ``rcond``).
    """
    joints = _loop_revolutes(queries)
    if not joints or not queries.closures:
        return ""
    data = queries.compute(q)
    Jc = queries.jacobian_of(data)
    extra, extra_twists = _extra_columns(queries, data, joints)
    free = np.hstack([Jc[:, queries.free_v], extra])
    nv = queries.model.nv + 2 * len(joints)  # a spherical joint adds two rotations
    n_free = queries.free_v.size + 2 * len(joints)
    rank, rank_free = _rank(np.hstack([Jc, extra]), rcond), _rank(free, rcond)
    mobility = nv - rank - (n_free - rank_free)
    n_act = len(queries.actuated)
    if mobility != n_act:
        return ""
    # the idle motions of the spherical joints (a rod spinning) must not move the tool
    fid = queries.frame_id(queries.measured_frame)
    Jm = six_by_nv(pin.getFrameJacobian(queries.model, data, fid, pin.LOCAL))[:, queries.free_v]
    idle = np.linalg.svd(free)[2][rank_free:].T
    if idle.size and np.any(np.linalg.norm(np.hstack([Jm, extra_twists]) @ idle, axis=0) > 1e-9):
        return ""
    names = [queries.model.names[j] for j in joints]
    return (
        f" The loops' point ('3d') closures need ball ends: if {', '.join(names)} "
        f"{'are' if len(names) > 1 else 'is'} meant to be spherical (a rod's ball end), "
        f"declare {'them' if len(names) > 1 else 'it'} in the sidecar with "
        f"'joint_name: [{', '.join(names)}]' and 'joint_type: SPHERICAL' (MJCF: "
        f'type="ball"); the mobility is then {mobility}, the {n_act} actuated joints.'
    )


def open_loop_hint(queries: KinematicQueries, q: np.ndarray, rcond: float) -> str:
    """A sentence for a closure that stays open at configuration ``q`` (nq,), or ``""``.

    Non-empty when the point closures' loops hold passive revolute joints, the closure
    residual at ``q`` is not removable to first order by the joints as declared (what
    is left after its least-squares projection on the closure Jacobian's range is more
    than 10× what is left with them), but is with ball ends at those joints (less than
    1e-3 of it left): rods drawn in a direction their revolute elbow cannot turn to.
    """
    joints = _loop_revolutes(queries)
    if not joints:
        return ""
    data = queries.compute(q)
    r = queries.residual_of(data)
    size = float(np.linalg.norm(r))
    if size == 0.0:
        return ""
    Jc = queries.jacobian_of(data)
    extra, _ = _extra_columns(queries, data, joints)

    def left(J: np.ndarray) -> float:
        step = np.linalg.lstsq(J, r, rcond=rcond)[0]
        return float(np.linalg.norm(r - J @ step))

    plain, balls = left(Jc), left(np.hstack([Jc, extra]))
    if balls > 1e-3 * size or plain <= 10.0 * balls:
        return ""
    names = [queries.model.names[j] for j in joints]
    return (
        f" The revolute joints on the point ('3d') closures' loops cannot turn the rods "
        f"onto their anchors ({plain / size:.0%} of the residual left to first order), ball "
        f"ends can: if {', '.join(names)} {'are' if len(names) > 1 else 'is'} meant to be "
        f"spherical, declare {'them' if len(names) > 1 else 'it'} in the sidecar with "
        f"'joint_name: [{', '.join(names)}]' and 'joint_type: SPHERICAL' (MJCF: "
        f'type="ball").'
    )
