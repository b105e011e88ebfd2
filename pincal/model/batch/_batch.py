"""Kinematics of a Pinocchio model for N configurations at once, in numpy.

:class:`BatchModel` walks the kinematic tree of a ``pin.Model`` once per call for a
whole batch of configurations ``Q`` (N, nq): every joint placement is a batched SE(3)
product, every joint's motion-subspace columns a batched adjoint. It reproduces
``pin.computeJointJacobians`` + ``pin.updateFramePlacements`` (placements ``oMi``,
``oMf`` and the WORLD joint Jacobian) and ``pin.integrate`` for the joint types the
loader produces: revolute (axis-aligned, unaligned, unbounded), prismatic
(axis-aligned, unaligned), universal (unit axes), planar, spherical and free-flyer
joints. A model with another joint type (or a universal joint with non-unit axes) is
reported by :attr:`BatchModel.supported` = False and callers fall back to Pinocchio
pose by pose. Pinocchio stays the reference: the tests compare both to 1e-12.
"""

from __future__ import annotations

import copy
import dataclasses
from collections.abc import Collection
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pincal.model.batch._batch_joints import planar_integrate
from pincal.model.batch._batch_ops import (
    cross_cols,
    exp3_batch,
    group_joints,
    joint_layout,
    mm,
    mv,
    quat_to_matrix,
    walk,
)
from pincal.model.batch._batch_ops import sinc_terms as _sinc_terms
from pincal.model.batch._batch_ops import skew as _skew
from pincal.model.batch._block_solve import PassiveFactor

__all__ = [
    "BatchKinematics",
    "BatchModel",
    "cross_cols",
    "exp3_batch",
    "mm",
    "mv",
    "quat_to_matrix",
    "slice_kinematics",
]

_AXES = {"X": (1.0, 0.0, 0.0), "Y": (0.0, 1.0, 0.0), "Z": (0.0, 0.0, 1.0)}


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
    kind: str  # "R", "RU" unbounded revolute, "P", "U" universal, "PL" planar, "S", "F"
    parent: int
    iq: int
    iv: int
    axis: np.ndarray  # (3,) unit axis (R, RU, P), first axis (U), z (PL)
    axis2: np.ndarray  # (3,) second axis (U)
    K: np.ndarray  # (3, 3) skew(axis)
    R0: np.ndarray  # (3, 3) rotation of the joint placement in its parent
    p0: np.ndarray  # (3,) translation of the joint placement


def _joint_kind(jm: pin.JointModel) -> tuple[str, np.ndarray, np.ndarray] | None:
    """Kind, axis and second axis of a joint, None when not implemented here."""
    name = jm.shortname()
    none = np.zeros(3)
    for prefix, kind in (("JointModelRUB", "RU"), ("JointModelR", "R"), ("JointModelP", "P")):
        if name.startswith(prefix) and name[len(prefix) :] in _AXES:
            return kind, np.array(_AXES[name[len(prefix) :]]), none
    unaligned = {
        "JointModelRevoluteUnaligned": "R",
        "JointModelRevoluteUnboundedUnaligned": "RU",
        "JointModelPrismaticUnaligned": "P",
    }
    if name in unaligned:
        return unaligned[name], np.array(jm.extract().axis, dtype=float), none
    if name == "JointModelUniversal":
        a, b = (np.array(x, dtype=float) for x in (jm.extract().axis1, jm.extract().axis2))
        # Pinocchio does not normalise the axes; its placement is no rotation otherwise
        unit = abs(np.linalg.norm(a) - 1.0) < 1e-12 and abs(np.linalg.norm(b) - 1.0) < 1e-12
        return ("U", a, b) if unit else None
    if name == "JointModelPlanar":
        return "PL", np.array(_AXES["Z"]), none
    if name == "JointModelSpherical":
        return "S", none, none
    if name == "JointModelFreeFlyer":
        return "F", none, none
    return None


@dataclass(frozen=True)
class BatchKinematics:
    """Kinematics of N configurations (the batched counterpart of ``pin.Data``).

    Attributes:
        q: (N, nq) configurations.
        rotations: (N, njoints, 3, 3) joint world rotations (``oMi``).
        translations: (N, njoints, 3) joint world positions [m].
        jacobian: (N, 6, nv) WORLD joint Jacobian ``[v_o; ω]`` (``data.J`` of Pinocchio).
        closure_jacobian: (N, n_closure_rows, k) closure Jacobian on the mechanism's k
            free dofs at ``q``, when the loop-closing solve computed it (else None).
        closure_factor: its factorisation (computed by the solve's branch
            and condition checks, reused by the sensitivities), else None.
    """

    q: np.ndarray
    rotations: np.ndarray
    translations: np.ndarray
    jacobian: np.ndarray
    closure_jacobian: np.ndarray | None = None
    closure_factor: PassiveFactor | None = None


def slice_kinematics(bk: BatchKinematics, rows: slice) -> BatchKinematics:
    """The kinematics of poses ``rows`` (views, not copies)."""
    cj, ci = bk.closure_jacobian, bk.closure_factor
    return BatchKinematics(
        bk.q[rows],
        bk.rotations[rows],
        bk.translations[rows],
        bk.jacobian[rows],
        None if cj is None else cj[rows],
        None if ci is None else ci.take(rows),
    )


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
            joints.append(  # the placements R0, p0 are taken by _place
                _Joint(kind[0], int(model.parents[j]), jm.idx_q, jm.idx_v, kind[1], kind[2],
                       _skew(kind[1]), np.eye(3), np.zeros(3))
            )  # fmt: skip
        #: False when the model has a joint type this module does not implement
        self.supported = ok
        self._joints = tuple(joints) if ok else ()
        self._place(model)
        # vector-space joints (q and v coordinates alike): R, P and the two angles of U
        linear = [
            (jt.iq + k, jt.iv + k)
            for jt in self._joints
            for k in range(2 if jt.kind == "U" else 1)
            if jt.kind in ("R", "P", "U")
        ]
        self._linear_q = np.array([i for i, _ in linear], dtype=int)
        self._linear_v = np.array([i for _, i in linear], dtype=int)
        support = np.zeros((model.njoints, model.nv), dtype=bool)
        for j in range(1, model.njoints):
            support[j] = support[model.parents[j]]
            support[j, model.idx_vs[j] : model.idx_vs[j] + model.nvs[j]] = True
        self._support = support

    def _place(
        self,
        model: pin.Model,
        joints: Collection[int] | None = None,
        frames: Collection[int] | None = None,
    ) -> None:
        """Take the joint and frame placements of ``model`` (same structure as built).

        ``joints`` / ``frames``: the joint ids and frame indices whose placements
        changed since the last call (None: all).
        """
        if self._joints:
            moved = list(self._joints)
            for j in range(1, model.njoints) if joints is None else joints:
                M = model.jointPlacements[j]
                moved[j - 1] = dataclasses.replace(
                    moved[j - 1], R0=M.rotation.copy(), p0=M.translation.copy()
                )
            self._joints = tuple(moved)
        placed = self._joints
        if self.supported and getattr(self, "_layout", None) is None:
            # the tree's grouping, kept by every copy: only placements move
            self._layout = joint_layout(
                [jt.kind for jt in placed], [jt.parent for jt in placed],
                [jt.iq for jt in placed], [jt.iv for jt in placed],
            )  # fmt: skip
        self._groups = (
            group_joints(
                [jt.kind for jt in placed],
                [jt.parent for jt in placed],
                [jt.iq for jt in placed],
                [jt.iv for jt in placed],
                np.array([jt.axis for jt in placed]).reshape(-1, 3),
                np.array([jt.R0 for jt in placed]).reshape(-1, 3, 3),
                np.array([jt.p0 for jt in placed]).reshape(-1, 3),
                np.array([jt.axis2 for jt in placed]).reshape(-1, 3),
                self._layout,
            )
            if self.supported
            else ()
        )
        if frames is None:
            self._frame_parent = np.array([f.parentJoint for f in model.frames], dtype=int)
            self._frame_R = np.empty((model.nframes, 3, 3))
            self._frame_p = np.empty((model.nframes, 3))
        else:
            self._frame_R, self._frame_p = self._frame_R.copy(), self._frame_p.copy()
        for i in range(model.nframes) if frames is None else frames:
            M = model.frames[i].placement
            self._frame_R[i], self._frame_p[i] = M.rotation, M.translation

    def with_placements(
        self,
        model: pin.Model,
        joints: Collection[int] | None = None,
        frames: Collection[int] | None = None,
    ) -> BatchModel:
        """This batched model with the joint and frame placements of ``model``.

        Args:
            model: a copy of this one's ``pin.Model`` whose placements were moved
                (:mod:`pincal.model._placements`); the joint kinds and the tree are kept.
            joints: the joint ids whose placements moved (None: all).
            frames: the frame indices whose placements moved (None: all).
        """
        new = copy.copy(self)
        new._place(model, joints, frames)
        return new

    # ------------------------------------------------------------------ kinematics
    def kinematics(self, Q: np.ndarray) -> BatchKinematics:
        """Joint placements and the WORLD joint Jacobian of configurations ``Q`` (N, nq)."""
        Q = np.asarray(Q, dtype=float)
        oR, op, Jw = walk(self._groups, Q, self.njoints, self.nv)
        return BatchKinematics(Q, oR, op, Jw)

    def frame_placement(self, bk: BatchKinematics, fid: int) -> tuple[np.ndarray, np.ndarray]:
        """World rotation (N, 3, 3) and position (N, 3) of frame ``fid``."""
        parent, R0, p0 = self._frame_parent[fid], self._frame_R[fid], self._frame_p[fid]
        Rp, pp = bk.rotations[:, parent], bk.translations[:, parent]
        return mm(Rp, R0), pp + mv(Rp, p0)

    def frame_placements(
        self, bk: BatchKinematics, fids: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """World rotations (N, G, 3, 3) and positions (N, G, 3) of frames ``fids`` (G,)."""
        parents = self._frame_parent[fids]
        Rp = bk.rotations[:, parents]
        return Rp @ self._frame_R[fids], bk.translations[:, parents] + mv(Rp, self._frame_p[fids])

    def frame_positions(self, bk: BatchKinematics, fids: np.ndarray) -> np.ndarray:
        """World positions (N, G, 3) of frames ``fids`` (G,) [m]."""
        parents = self._frame_parent[fids]
        return bk.translations[:, parents] + mv(bk.rotations[:, parents], self._frame_p[fids])

    def support_of_frame(self, fid: int) -> np.ndarray:
        """(nv,) True for the tangent dofs that move frame ``fid`` (its supporting joints)."""
        return self._support[self._frame_parent[fid]]

    def frame_jacobian(
        self, bk: BatchKinematics, fid: int, local_world_aligned: bool = False
    ) -> np.ndarray:
        """(N, 6, nv) LOCAL (or LOCAL_WORLD_ALIGNED) Jacobian ``[v; ω]`` of frame ``fid``."""
        R, p = self.frame_placement(bk, fid)
        cols = self._support[self._frame_parent[fid]]
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
        out[:, self._linear_q] += DV[:, self._linear_v]
        for jt in self._joints:
            iq, iv = jt.iq, jt.iv
            if jt.kind in ("R", "P", "U"):
                continue
            if jt.kind == "PL":
                out[:, iq : iq + 4] = planar_integrate(Q[:, iq : iq + 4], DV[:, iv : iv + 3])
                continue
            if jt.kind == "RU":
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
                quat = _quat_mul_exp(Q[:, iq + 3 : iq + 7], w)
                # Pinocchio's SE(3) integrate keeps the quaternion in q's hemisphere
                # (its spherical joint does not: q ⊗ exp(w) as it comes)
                flip = np.sum(quat * Q[:, iq + 3 : iq + 7], axis=1) < 0.0
                out[:, iq + 3 : iq + 7] = np.where(flip[:, None], -quat, quat)
        return out
