"""Kinematics of a Pinocchio model for N configurations at once, in numpy.

:class:`BatchModel` walks the kinematic tree of a ``pin.Model`` once per call for a
whole batch of configurations ``Q`` (N, nq): every joint placement is a batched SE(3)
product, every joint's motion-subspace columns a batched adjoint. It reproduces
``pin.computeJointJacobians`` + ``pin.updateFramePlacements`` (placements ``oMi``,
``oMf`` and the WORLD joint Jacobian) and ``pin.integrate`` for the joint types the
loader produces: revolute (axis-aligned, unaligned, unbounded), prismatic
(axis-aligned, unaligned), spherical and free-flyer joints. A model with another joint
type is reported by :attr:`BatchModel.supported` = False and callers fall back to
Pinocchio pose by pose. Pinocchio stays the reference: the tests compare both to 1e-12.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

__all__ = [
    "BatchKinematics",
    "BatchModel",
    "cross_cols",
    "exp3_batch",
    "mm",
    "mv",
    "quat_to_matrix",
]

_AXES = {"X": (1.0, 0.0, 0.0), "Y": (0.0, 1.0, 0.0), "Z": (0.0, 0.0, 1.0)}


def mm(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Stacked products ``A @ B`` of (…, 3, 3) by (…, 3, k) as three broadcast terms.

    numpy's stacked matmul loops over 3 × 3 matrices one by one; three whole-array
    multiply-adds are an order of magnitude faster (same summation order).
    """
    return (
        A[..., :, 0:1] * B[..., 0:1, :]
        + A[..., :, 1:2] * B[..., 1:2, :]
        + (A[..., :, 2:3] * B[..., 2:3, :])
    )


def mv(A: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Stacked products ``A @ v`` of (…, 3, 3) by vectors (…, 3)."""
    return A[..., :, 0] * v[..., 0:1] + A[..., :, 1] * v[..., 1:2] + A[..., :, 2] * v[..., 2:3]


def cross_cols(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Column-wise cross products ``a × b`` of (N, 3, k) arrays (broadcasting)."""
    a0, a1, a2 = a[:, 0], a[:, 1], a[:, 2]
    b0, b1, b2 = b[:, 0], b[:, 1], b[:, 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=1)


def _skew(v: np.ndarray) -> np.ndarray:
    """(…, 3, 3) skew matrices of vectors (…, 3)."""
    out = np.zeros((*v.shape[:-1], 3, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


def _sinc_terms(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Sin θ/θ, (1 − cos θ)/θ², (θ − sin θ)/θ³ with Taylor series near 0 (arrays (N,))."""
    small = theta < 1e-4
    t = np.where(small, 1.0, theta)
    t2 = theta * theta
    a = np.where(small, 1.0 - t2 / 6.0, np.sin(t) / t)
    b = np.where(small, 0.5 - t2 / 24.0, (1.0 - np.cos(t)) / (t * t))
    c = np.where(small, 1.0 / 6.0 - t2 / 120.0, (t - np.sin(t)) / (t * t * t))
    return a, b, c


def exp3_batch(w: np.ndarray) -> np.ndarray:
    """Rotation matrices (N, 3, 3) of rotation vectors (N, 3) [rad] (Rodrigues)."""
    theta = np.linalg.norm(w, axis=-1)
    a, b, _ = _sinc_terms(theta)
    K = _skew(w)
    return np.eye(3) + a[:, None, None] * K + b[:, None, None] * (K @ K)


def quat_to_matrix(quat: np.ndarray) -> np.ndarray:
    """Rotation matrices (N, 3, 3) of unit quaternions (N, 4) stored x, y, z, w."""
    x, y, z, w = quat[:, 0], quat[:, 1], quat[:, 2], quat[:, 3]
    tx, ty, tz = 2 * x, 2 * y, 2 * z
    twx, twy, twz = tx * w, ty * w, tz * w
    txx, txy, txz = tx * x, ty * x, tz * x
    tyy, tyz, tzz = ty * y, tz * y, tz * z
    R = np.empty((quat.shape[0], 3, 3))
    R[:, 0, 0], R[:, 0, 1], R[:, 0, 2] = 1 - (tyy + tzz), txy - twz, txz + twy
    R[:, 1, 0], R[:, 1, 1], R[:, 1, 2] = txy + twz, 1 - (txx + tzz), tyz - twx
    R[:, 2, 0], R[:, 2, 1], R[:, 2, 2] = txz - twy, tyz + twx, 1 - (txx + tyy)
    return R


def _axis_rotation(axis: np.ndarray, c: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Rotations (N, 3, 3) about a unit axis (3,) of angles given by cos, sin (N,)."""
    N = c.shape[0]
    nz = np.nonzero(axis)[0]
    if nz.size == 1 and axis[nz[0]] == 1.0:  # aligned axis: exact cos/sin entries
        k = int(nz[0])
        a, b = (k + 1) % 3, (k + 2) % 3
        R = np.zeros((N, 3, 3))
        R[:, k, k] = 1.0
        R[:, a, a], R[:, b, b] = c, c
        R[:, a, b], R[:, b, a] = -s, s
        return R
    t = 1.0 - c
    R = (t[:, None, None] * np.outer(axis, axis)) + c[:, None, None] * np.eye(3)
    return R + s[:, None, None] * _skew(axis)


def _quat_mul_exp(quat: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Unit quaternions (N, 4) (x, y, z, w) of ``quat ⊗ exp(w)`` for rotation vectors (N, 3)."""
    theta = np.linalg.norm(w, axis=1)
    small = theta < 1e-4
    t = np.where(small, 1.0, theta)
    half = np.where(small, 0.5 - theta**2 / 48.0, np.sin(0.5 * t) / t)
    e = np.concatenate([half[:, None] * w, np.cos(0.5 * theta)[:, None]], axis=1)
    v1, s1, v2, s2 = quat[:, :3], quat[:, 3], e[:, :3], e[:, 3]
    out = np.empty_like(quat)
    out[:, :3] = s1[:, None] * v2 + s2[:, None] * v1 + np.cross(v1, v2)
    out[:, 3] = s1 * s2 - np.sum(v1 * v2, axis=1)
    return out / np.linalg.norm(out, axis=1, keepdims=True)


@dataclass(frozen=True)
class _Joint:
    kind: str  # "R" revolute, "RU" unbounded revolute, "P" prismatic, "S", "F" free flyer
    parent: int
    iq: int
    iv: int
    axis: np.ndarray  # (3,) unit axis (R, RU, P)
    K: np.ndarray  # (3, 3) skew(axis)
    R0: np.ndarray  # (3, 3) rotation of the joint placement in its parent
    p0: np.ndarray  # (3,) translation of the joint placement


def _joint_kind(jm: pin.JointModel) -> tuple[str, np.ndarray] | None:
    name = jm.shortname()
    for prefix, kind in (("JointModelRUB", "RU"), ("JointModelR", "R"), ("JointModelP", "P")):
        if name.startswith(prefix) and name[len(prefix) :] in _AXES:
            return kind, np.array(_AXES[name[len(prefix) :]])
    unaligned = {
        "JointModelRevoluteUnaligned": "R",
        "JointModelRevoluteUnboundedUnaligned": "RU",
        "JointModelPrismaticUnaligned": "P",
    }
    if name in unaligned:
        return unaligned[name], np.array(jm.extract().axis, dtype=float)
    if name == "JointModelSpherical":
        return "S", np.zeros(3)
    if name == "JointModelFreeFlyer":
        return "F", np.zeros(3)
    return None


@dataclass(frozen=True)
class BatchKinematics:
    """Kinematics of N configurations (the batched counterpart of ``pin.Data``).

    Attributes:
        q: (N, nq) configurations.
        rotations: (N, njoints, 3, 3) joint world rotations (``oMi``).
        translations: (N, njoints, 3) joint world positions [m].
        jacobian: (N, 6, nv) WORLD joint Jacobian ``[v_o; ω]`` (``data.J`` of Pinocchio).
    """

    q: np.ndarray
    rotations: np.ndarray
    translations: np.ndarray
    jacobian: np.ndarray


class BatchModel:
    """Batched forward kinematics, frame Jacobians and integration of a ``pin.Model``.

    Args:
        model: the Pinocchio model (not modified, not kept beyond its constants).
    """

    def __init__(self, model: pin.Model):
        self.nq, self.nv, self.njoints = model.nq, model.nv, model.njoints
        joints, ok = [], True
        for j in range(1, model.njoints):
            jm = model.joints[j]
            kind = _joint_kind(jm)
            if kind is None:
                ok = False
                break
            M = model.jointPlacements[j]
            joints.append(
                _Joint(
                    kind[0],
                    int(model.parents[j]),
                    jm.idx_q,
                    jm.idx_v,
                    kind[1],
                    _skew(kind[1]),
                    M.rotation.copy(),
                    M.translation.copy(),
                )
            )
        #: False when the model has a joint type this module does not implement
        self.supported = ok
        self._joints = tuple(joints) if ok else ()
        self._frames = [
            (int(f.parentJoint), f.placement.rotation.copy(), f.placement.translation.copy())
            for f in model.frames
        ]
        support = np.zeros((model.njoints, model.nv), dtype=bool)
        for j in range(1, model.njoints):
            support[j] = support[model.parents[j]]
            support[j, model.idx_vs[j] : model.idx_vs[j] + model.nvs[j]] = True
        self._support = support

    # ------------------------------------------------------------------ kinematics
    def kinematics(self, Q: np.ndarray) -> BatchKinematics:
        """Joint placements and the WORLD joint Jacobian of configurations ``Q`` (N, nq)."""
        Q = np.asarray(Q, dtype=float)
        N = Q.shape[0]
        oR = np.empty((N, self.njoints, 3, 3))
        op = np.empty((N, self.njoints, 3))
        oR[:, 0], op[:, 0] = np.eye(3), 0.0
        Jw = np.zeros((N, 6, self.nv))
        for j, jt in enumerate(self._joints, start=1):
            # Pinocchio's order: liMi = placement · M_joint(q), oMi = oM_parent · liMi
            Rp, pp = oR[:, jt.parent], op[:, jt.parent]
            if jt.kind in ("R", "RU"):
                if jt.kind == "R":
                    th = Q[:, jt.iq]
                    s, c = np.sin(th), np.cos(th)
                else:
                    c, s = Q[:, jt.iq], Q[:, jt.iq + 1]
                liR = mm(jt.R0, _axis_rotation(jt.axis, c, s))
                lip = np.broadcast_to(jt.p0, (N, 3))
            elif jt.kind == "P":
                liR = np.broadcast_to(jt.R0, (N, 3, 3))
                lip = jt.p0 + mv(jt.R0, Q[:, jt.iq, None] * jt.axis)
            else:
                i4 = jt.iq + (3 if jt.kind == "F" else 0)
                liR = mm(jt.R0, quat_to_matrix(Q[:, i4 : i4 + 4]))
                lip = np.broadcast_to(jt.p0, (N, 3))
                if jt.kind == "F":
                    lip = jt.p0 + mv(jt.R0, Q[:, jt.iq : jt.iq + 3])
            Ri = mm(Rp, liR)
            pi = pp + mv(Rp, lip)
            oR[:, j], op[:, j] = Ri, pi
            if jt.kind in ("R", "RU"):
                w = mv(Ri, jt.axis)
                Jw[:, 3:, jt.iv] = w
                Jw[:, :3, jt.iv] = cross_cols(pi[:, :, None], w[:, :, None])[..., 0]
            elif jt.kind == "P":
                Jw[:, :3, jt.iv] = mv(Ri, jt.axis)
            else:
                v0 = jt.iv
                if jt.kind == "F":  # local linear velocity columns
                    Jw[:, :3, v0 : v0 + 3] = Ri
                    v0 += 3
                Jw[:, 3:, v0 : v0 + 3] = Ri
                Jw[:, :3, v0 : v0 + 3] = cross_cols(pi[:, :, None], Ri)
        return BatchKinematics(Q, oR, op, Jw)

    def frame_placement(self, bk: BatchKinematics, fid: int) -> tuple[np.ndarray, np.ndarray]:
        """World rotation (N, 3, 3) and position (N, 3) of frame ``fid``."""
        parent, R0, p0 = self._frames[fid]
        Rp, pp = bk.rotations[:, parent], bk.translations[:, parent]
        return mm(Rp, R0), pp + mv(Rp, p0)

    def support_of_frame(self, fid: int) -> np.ndarray:
        """(nv,) True for the tangent dofs that move frame ``fid`` (its supporting joints)."""
        return self._support[self._frames[fid][0]]

    def frame_jacobian(
        self, bk: BatchKinematics, fid: int, local_world_aligned: bool = False
    ) -> np.ndarray:
        """(N, 6, nv) LOCAL (or LOCAL_WORLD_ALIGNED) Jacobian ``[v; ω]`` of frame ``fid``."""
        R, p = self.frame_placement(bk, fid)
        cols = self._support[self._frames[fid][0]]
        J = np.zeros_like(bk.jacobian)
        Jv, Jw = bk.jacobian[:, :3, cols], bk.jacobian[:, 3:, cols]
        v = Jv + cross_cols(Jw, p[:, :, None])  # velocity of the frame origin
        if local_world_aligned:
            J[:, :3, cols], J[:, 3:, cols] = v, Jw
        else:
            Rt = np.swapaxes(R, 1, 2)
            J[:, :3, cols], J[:, 3:, cols] = mm(Rt, v), mm(Rt, Jw)
        return J

    # ------------------------------------------------------------------ integration
    def integrate(self, Q: np.ndarray, DV: np.ndarray) -> np.ndarray:
        """``pin.integrate`` of configurations (N, nq) by tangent steps (N, nv)."""
        out = np.array(Q, dtype=float)
        for jt in self._joints:
            iq, iv = jt.iq, jt.iv
            if jt.kind in ("R", "P"):
                out[:, iq] += DV[:, iv]
            elif jt.kind == "RU":
                c, s = Q[:, iq], Q[:, iq + 1]
                cd, sd = np.cos(DV[:, iv]), np.sin(DV[:, iv])
                cn, sn = c * cd - s * sd, s * cd + c * sd
                norm = np.hypot(cn, sn)
                out[:, iq], out[:, iq + 1] = cn / norm, sn / norm
            elif jt.kind == "S":
                out[:, iq : iq + 4] = _quat_mul_exp(Q[:, iq : iq + 4], DV[:, iv : iv + 3])
            else:  # free flyer: M · exp6(v), v = [linear; angular] in the local frame
                v, w = DV[:, iv : iv + 3], DV[:, iv + 3 : iv + 6]
                theta = np.linalg.norm(w, axis=1)
                _, b, c = _sinc_terms(theta)
                K = _skew(w)
                V = np.eye(3) + b[:, None, None] * K + c[:, None, None] * (K @ K)
                R = quat_to_matrix(Q[:, iq + 3 : iq + 7])
                out[:, iq : iq + 3] = Q[:, iq : iq + 3] + (R @ (V @ v[:, :, None]))[..., 0]
                out[:, iq + 3 : iq + 7] = _quat_mul_exp(Q[:, iq + 3 : iq + 7], w)
        return out
