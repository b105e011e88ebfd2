"""Small batched array operations and the grouped tree walk of the batched kinematics.

The helpers act on stacks of 3-vectors and 3 × 3 matrices (leading axes are poses and,
for grouped joints, joints). :func:`walk` computes the joint placements and the WORLD
joint Jacobian of N configurations, visiting the tree by :class:`JointGroup`: the
joints of one type at one depth are computed together (all legs of a parallel machine
in one set of array operations), which is what keeps the Python overhead per tree node
small. Pinocchio stays the reference (tests compare to 1e-12).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pincal.model.batch._batch_joints import cross3, planar_step, universal_factors, universal_step

__all__ = [
    "JointGroup",
    "cross3",
    "cross_cols",
    "exp3_batch",
    "group_joints",
    "jlog3_batch",
    "joint_layout",
    "log3_batch",
    "mm",
    "mv",
    "quat_to_matrix",
    "sinc_terms",
    "skew",
    "walk",
]


def mm(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Stacked products ``A @ B`` of (…, 3, 3) by (…, 3, k) as three broadcast terms."""
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


def skew(v: np.ndarray) -> np.ndarray:
    """(…, 3, 3) skew matrices of vectors (…, 3)."""
    out = np.zeros((*v.shape[:-1], 3, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


def sinc_terms(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
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
    a, b, _ = sinc_terms(theta)
    K = skew(w)
    return np.eye(3) + a[:, None, None] * K + b[:, None, None] * (K @ K)


def quat_to_matrix(quat: np.ndarray) -> np.ndarray:
    """Rotation matrices (…, 3, 3) of unit quaternions (…, 4) stored x, y, z, w."""
    x, y, z, w = quat[..., 0], quat[..., 1], quat[..., 2], quat[..., 3]
    tx, ty, tz = 2 * x, 2 * y, 2 * z
    twx, twy, twz = tx * w, ty * w, tz * w
    txx, txy, txz = tx * x, ty * x, tz * x
    tyy, tyz, tzz = ty * y, tz * y, tz * z
    R = np.empty((*quat.shape[:-1], 3, 3))
    R[..., 0, 0], R[..., 0, 1], R[..., 0, 2] = 1 - (tyy + tzz), txy - twz, txz + twy
    R[..., 1, 0], R[..., 1, 1], R[..., 1, 2] = txy + twz, 1 - (txx + tzz), tyz - twx
    R[..., 2, 0], R[..., 2, 1], R[..., 2, 2] = txz - twy, tyz + twx, 1 - (txx + tyy)
    return R


@dataclass(frozen=True)
class JointGroup:
    """Joints of one type at one depth of the tree (computed together).

    Attributes:
        kind: "R" revolute, "RU" unbounded revolute, "P" prismatic, "U" universal,
            "PL" planar, "S" spherical, "F" free flyer.
        ids, parents, iq, iv: (G,) joint ids, parent ids, first q and v indices.
        R0, p0: (G, 3, 3), (G, 3) joint placements in their parents.
        C: (G, 3, 11) the constant right factors ``[R0, R0·K, R0·K², R0·axis, p0]``
            (K = skew(axis)) multiplied by the parent rotation in one product: the
            Rodrigues terms of the joint rotation, the world axis and the world offset
            (a universal joint's first axis; z for a planar joint).
        root: every parent is the universe (its rotation is the identity).
        D: (G, 3, 7) universal joints' second-axis factors ``[b, Kb, Kb²]`` (else None).
    """

    kind: str
    ids: np.ndarray
    parents: np.ndarray
    iq: np.ndarray
    iv: np.ndarray
    R0: np.ndarray
    p0: np.ndarray
    C: np.ndarray
    root: bool
    D: np.ndarray | None = None


def group_joints(
    kinds: Sequence[str],
    parents: Sequence[int],
    iq: Sequence[int],
    iv: Sequence[int],
    axes: np.ndarray,
    R0: np.ndarray,
    p0: np.ndarray,
    axes2: np.ndarray | None = None,
    layout: Layout | None = None,
) -> tuple[JointGroup, ...]:
    """Groups of joints 1 … njoints−1 (given per joint, in id order) by depth and type.

    ``axes`` (njoints−1, 3) are the joints' (first) axes, ``axes2`` the second axes of
    universal joints (rows of other joints are ignored; needed when there is one).
    ``layout``: :func:`joint_layout` of these kinds and parents, when the caller keeps
    it (the tree does not change when only placements move).
    """
    if layout is None:
        layout = joint_layout(kinds, parents, iq, iv)
    groups = []
    for kind, ids, par, gq, gv in layout:
        k = ids - 1
        K = skew(axes[k])
        R, a, p = R0[k], axes[k], p0[k]
        C = np.concatenate([R, R @ K, R @ K @ K, mv(R, a)[..., None], p[..., None]], axis=2)
        groups.append(
            JointGroup(
                kind,
                ids,
                par,
                gq,
                gv,
                R,
                p,
                C,
                bool(np.all(par == 0)),
                universal_factors(axes2[k], skew(axes2[k]))
                if kind == "U" and axes2 is not None
                else None,
            )
        )
    return tuple(groups)


#: per group: (kind, joint ids, parent ids, first q index, first v index)
Layout = tuple[tuple[str, np.ndarray, np.ndarray, np.ndarray, np.ndarray], ...]


def joint_layout(
    kinds: Sequence[str], parents: Sequence[int], iq: Sequence[int], iv: Sequence[int]
) -> Layout:
    """The groups of :func:`group_joints` (by depth and type) without their placements."""
    depth = [0]
    keys: dict[tuple[int, str], list[int]] = {}
    for j, (kind, parent) in enumerate(zip(kinds, parents, strict=True), start=1):
        depth.append(depth[parent] + 1)
        keys.setdefault((depth[j], kind), []).append(j)
    out = []
    for (_, kind), ids in sorted(keys.items()):
        k = np.array(ids) - 1
        out.append((kind, np.array(ids), np.array([parents[i] for i in k]),
                    np.array([iq[i] for i in k]), np.array([iv[i] for i in k])))  # fmt: skip
    return tuple(out)


def _step(
    g: JointGroup, Q: np.ndarray, Rp: np.ndarray, pp: np.ndarray, Jt: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """World rotations (G, N, 3, 3) and positions (G, N, 3) of group ``g``'s joints.

    Writes their WORLD Jacobian columns into ``Jt`` (nv, N, 6). ``Rp``, ``pp``: the
    parents' world rotations (G, N, 3, 3) and positions (G, N, 3).
    """
    G, N = Rp.shape[:2]
    q = Q[:, g.iq].T  # (G, N) first coordinate of each joint
    if g.kind in ("R", "RU", "P", "U", "PL"):
        # one product per joint for all poses: Rp · [R0, R0K, R0K², u, p0]
        X = (Rp.reshape(G, N * 3, 3) @ g.C).reshape(G, N, 3, 11)
        if g.kind == "U":
            assert g.D is not None
            return universal_step(X, g.D, Q[:, g.iq[:, None] + np.arange(2)].T, pp, g.iv, Jt)
        if g.kind == "PL":
            return planar_step(X, Q[:, g.iq[:, None] + np.arange(4)].T, pp, g.iv, Jt)
        w, off = X[..., 9], X[..., 10]
        if g.kind == "P":
            Ri = X[..., 0:3]
            pi = pp + off + q[..., None] * w
            Jt[g.iv, :, :3] = w
            return np.ascontiguousarray(Ri), pi
        if g.kind == "R":
            c, s = np.cos(q), np.sin(q)
        else:
            c, s = q, Q[:, g.iq + 1].T
        Ri = (
            X[..., 0:3]
            + s[..., None, None] * X[..., 3:6]
            + (1.0 - c)[..., None, None] * X[..., 6:9]
        )
        pi = pp + off
        Jt[g.iv, :, 3:] = w
        Jt[g.iv, :, :3] = cross3(pi, w)
        return Ri, pi
    i4 = g.iq + (3 if g.kind == "F" else 0)
    quat = np.swapaxes(Q[:, i4[:, None] + np.arange(4)], 0, 1)  # (G, N, 4)
    liR = g.R0[:, None] @ quat_to_matrix(quat)
    lip = g.p0[:, None] + (
        mv(g.R0[:, None], np.swapaxes(Q[:, g.iq[:, None] + np.arange(3)], 0, 1))
        if g.kind == "F"
        else 0.0
    )
    if g.root:
        Ri, pi = liR, np.broadcast_to(lip, (G, N, 3)) + pp
    else:
        Ri, pi = Rp @ liR, pp + mv(Rp, np.broadcast_to(lip, (G, N, 3)))
    cols = np.swapaxes(Ri, 2, 3)  # (G, N, c, 3): the world axes
    v0 = g.iv + (3 if g.kind == "F" else 0)
    for a in range(3):
        if g.kind == "F":  # local linear velocity columns
            Jt[v0 - 3 + a, :, :3] = cols[:, :, a]
        Jt[v0 + a, :, 3:] = cols[:, :, a]
        Jt[v0 + a, :, :3] = cross3(pi, cols[:, :, a])
    return Ri, pi


def walk(
    groups: Sequence[JointGroup], Q: np.ndarray, njoints: int, nv: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """World rotations (N, njoints, 3, 3), positions (N, njoints, 3), WORLD Jacobian (N, 6, nv).

    Pinocchio's order: ``liMi = placement · M_joint(q)``, ``oMi = oM_parent · liMi``; a
    joint column of the WORLD Jacobian is the joint's motion subspace seen from the
    world origin (``[v_o; ω]``). The walk stores joints first (arrays (njoints, N, …)),
    so that a group's parent rotations form one matrix per joint and the constant
    factors of a revolute or prismatic group multiply them in one product per joint
    (numpy's stacked products of 3 × 3 matrices cost per matrix, not per flop).
    """
    N = Q.shape[0]
    oR = np.empty((njoints, N, 3, 3))
    op = np.empty((njoints, N, 3))
    oR[0], op[0] = np.eye(3), 0.0
    Jt = np.zeros((nv, N, 6))
    for g in groups:
        Ri, pi = _step(g, Q, oR[g.parents], op[g.parents], Jt)
        oR[g.ids], op[g.ids] = Ri, pi
    return (
        np.ascontiguousarray(np.swapaxes(oR, 0, 1)),
        np.ascontiguousarray(np.swapaxes(op, 0, 1)),
        np.ascontiguousarray(np.transpose(Jt, (1, 2, 0))),
    )


def log3_batch(R: np.ndarray) -> np.ndarray:
    """Rotation vectors (N, 3) [rad] of rotation matrices (N, 3, 3) (``pin.log3`` batched).

    θ = atan2(‖v‖, tr R − 1) with v = vee(R − Rᵀ) = 2 sin θ·axis keeps full precision
    for small angles; rotations beyond 2.5 rad (where v loses the axis near π) are
    handed to ``pin.log3`` one by one.
    """
    v = np.stack([R[:, 2, 1] - R[:, 1, 2], R[:, 0, 2] - R[:, 2, 0], R[:, 1, 0] - R[:, 0, 1]], 1)
    s = np.linalg.norm(v, axis=1)
    theta = np.arctan2(s, R[:, 0, 0] + R[:, 1, 1] + R[:, 2, 2] - 1.0)
    small = theta < 1e-4
    factor = np.where(small, 0.5 + theta * theta / 12.0, theta / np.where(small, 1.0, s))
    w = factor[:, None] * v
    for i in np.nonzero(theta > 2.5)[0]:
        w[i] = pin.log3(R[i])
    return w


def jlog3_batch(w: np.ndarray) -> np.ndarray:
    """(N, 3, 3) ``pin.Jlog3`` of the rotations exp(w) given their rotation vectors (N, 3).

    ``Jlog3 = I + ½[w]× + (1/θ² − (1 + cos θ)/(2θ sin θ))[w]×²`` (Taylor series below
    0.01 rad, where the difference cancels).
    """
    theta = np.linalg.norm(w, axis=1)
    small = theta < 1e-2
    t = np.where(small, 1.0, theta)
    t2 = theta * theta
    series = 1.0 / 12.0 + t2 * (1.0 / 720.0 + t2 * (1.0 / 30240.0 + t2 / 1209600.0))
    coef = np.where(small, series, 1.0 / (t * t) - (1.0 + np.cos(t)) / (2.0 * t * np.sin(t)))
    K = skew(w)
    return np.eye(3) + 0.5 * K + coef[:, None, None] * (K @ K)
