"""The batched identification Jacobian of a serial chain (no closures), body-wise.

Split from :mod:`pincal.sensitivity.batch._batch_jacobian` (same mathematics, a faster
formation for chains). Every parameterised joint origin j hangs at a constant placement
``C_j`` on a Pinocchio body k (the parent joint of a movable joint, the supporting joint
of a fixed one): ``A_j = oMi[k] · C_j``. A local twist ξ of that origin moves the
measured frame m by ``B_k · Ad(C_j) · ξ``, where the (6, 6) map

    B_k = [[R_k, [p_k − p_m]× R_k], [0, R_mᵀ R_k]]

gives the world velocity of m's origin and m's local angular velocity from a twist
expressed at body k's frame. Only the B_k depend on the pose; they are formed for a
block of poses and all bodies at once (poses on the innermost axis, a block sized to
stay in the L2 cache), and the columns of joint j are one stacked GEMM of the block's
B_k by the constant ``Ad(C_j) · eff_j`` (6, c_j), written straight into the result.
This is the right-multiplication structure of Pinocchio's
``computeFrameKinematicRegressor`` (the map from joint-placement twists to the frame's
twist) evaluated in numpy over the batch, on the placements the batched kinematics
already computed.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass

import numpy as np

from pincal.model import BatchKinematics, Linearisation, Mechanism, ParameterSet
from pincal.sensitivity._jacobian import JacobianPlan

__all__: list[str] = []

#: poses × bodies per block of body maps: a block's maps take 288 bytes × this ≈ 512 KB
#: (half the L2 cache of a core)
BLOCK = 1820
_scratch = threading.local()


def _scratch_maps(K: int, M: int) -> np.ndarray:
    """A (6, 6, K, M) scratch array, kept per thread between calls.

    A fresh block-sized array on every call is, depending on the allocator's state,
    fresh pages from the system each time: their page faults cost more than the
    arithmetic on a few hundred poses. The array only ever holds temporaries.
    """
    buf = getattr(_scratch, "maps", None)
    if buf is None or buf.shape != (6, 6, K, M):
        buf = _scratch.maps = np.empty((6, 6, K, M))
    return buf


def serial_columns(cols: np.ndarray) -> slice | np.ndarray:
    """A slice for contiguous parameter columns (faster to write), else the indices."""
    ks = cols.tolist()  # plain Python: a handful of columns, called per joint and call
    if ks and ks == list(range(ks[0], ks[0] + len(ks))):
        return slice(ks[0], ks[0] + len(ks))
    return cols


def anchors(
    mech: Mechanism, plan: JacobianPlan
) -> tuple[list[str], np.ndarray, np.ndarray, np.ndarray]:
    """Parameterised joints, their origins' parent joints (J,) and constant placements.

    Origin j = ``oMi[parent_j] · (R0_j, p0_j)`` with R0 (J, 3, 3), p0 (J, 3) [m].
    """
    model, names = mech.model, list(plan.origins)
    parents, R0, p0 = [], [], []
    for j in names:
        fid, jid, parent = plan.origins[j]
        M = model.frames[fid].placement if fid >= 0 else model.jointPlacements[jid]
        parents.append(model.frames[fid].parentJoint if fid >= 0 else parent)
        R0.append(M.rotation)
        p0.append(M.translation)
    return names, np.array(parents, dtype=int), np.array(R0), np.array(p0)


@dataclass(frozen=True)
class _Layout:
    """Which bodies carry the parameterised origins, and each joint's constant map.

    Attributes:
        bodies: the Pinocchio joint ids (ascending; 0 is the world) of the K bodies
            carrying an origin that moves the measured frame: a slice when they are
            consecutive, else a (K,) index array.
        size: K.
        runs: per such joint, (position of its body among the K, its parameter
            columns, the constant (6, c) map ``Ad(C_j) · eff_j``).
    """

    bodies: slice | np.ndarray
    size: int
    runs: tuple[tuple[int, slice | np.ndarray, np.ndarray], ...]


def _layout(
    mech: Mechanism, params: ParameterSet, values: np.ndarray | Linearisation, plan: JacobianPlan
) -> _Layout:
    """The :class:`_Layout` of the measured frame at parameter ``values``."""
    model = mech.model
    twists = params.linearise(values).joint_twists
    found = []
    for j in plan.moves[mech.measured_frame]:
        fid, jid, parent = plan.origins[j]
        if fid >= 0:
            body, C = int(model.frames[fid].parentJoint), model.frames[fid].placement
        else:
            body, C = int(parent), model.jointPlacements[jid]
        cols, _, eff = twists[j]
        found.append((body, serial_columns(cols), np.ascontiguousarray(C.action @ eff)))
    ids = sorted({f[0] for f in found})
    where = {b: k for k, b in enumerate(ids)}
    runs = tuple((where[b], c, G) for b, c, G in found)
    consecutive = bool(ids) and ids[-1] - ids[0] + 1 == len(ids)
    bodies = slice(ids[0], ids[-1] + 1) if consecutive else np.array(ids, dtype=int)
    return _Layout(bodies, len(ids), runs)


def _body_maps(
    bk: BatchKinematics,
    rows: slice,
    lay: _Layout,
    Rm: np.ndarray,
    pm: np.ndarray,
    buf: np.ndarray,
) -> np.ndarray:
    """The maps B_k of poses ``rows`` as a (6, 6, K, M) array (map row, map column, body, pose).

    Poses are the innermost axis, so every elementwise operation runs over long
    contiguous rows; the slice ``[:, :, k, :]`` transposed to (6, M, 6) is a stack of
    six GEMM operands (one per map row) without a copy.

    Args:
        bk: the batched kinematics.
        rows: the poses of this block (M of them).
        lay: the bodies.
        Rm: (M, 3, 3) measured frame rotations of these poses.
        pm: (M, 3) their positions [m].
        buf: (6, 6, K, ≥ M) scratch array the maps are written into (a view is returned).
    """
    b = lay.bodies
    R = bk.rotations[rows, b] if isinstance(b, slice) else bk.rotations[rows][:, b]
    p = bk.translations[rows, b] if isinstance(b, slice) else bk.translations[rows][:, b]
    M = R.shape[0]
    S = buf[..., :M]
    Rs = S[:3, :3]  # R_k[l, j] as (l, j, K, M)
    Rs[...] = R.transpose(2, 3, 1, 0)
    S[3:, :3] = 0.0
    e0, e1, e2 = np.subtract(p.transpose(2, 1, 0), pm.T[:, None], out=np.empty((3, lay.size, M)))
    np.multiply(e1, Rs[2], out=S[0, 3:])  # rows of [p_k − p_m]× R_k
    S[0, 3:] -= e2 * Rs[1]
    np.multiply(e2, Rs[0], out=S[1, 3:])
    S[1, 3:] -= e0 * Rs[2]
    np.multiply(e0, Rs[1], out=S[2, 3:])
    S[2, 3:] -= e1 * Rs[0]
    Rmt = np.ascontiguousarray(Rm.transpose(1, 2, 0))  # Rm[l, i] as (l, i, M)
    X = S[3:, 3:]  # R_mᵀ R_k: X[i, j] = Σ_l Rm[l, i] R_k[l, j]
    np.multiply(Rmt[0][:, None, None], Rs[0], out=X)
    X += Rmt[1][:, None, None] * Rs[1]
    X += Rmt[2][:, None, None] * Rs[2]
    return S


def _measured_placement(mech: Mechanism, bk: BatchKinematics) -> tuple[np.ndarray, np.ndarray]:
    """World rotations (N, 3, 3) and positions (N, 3) [m] of the measured frame (2 GEMMs)."""
    frame = mech.model.frames[mech.frame_id(mech.measured_frame)]
    N, parent = bk.q.shape[0], int(frame.parentJoint)
    Rp = bk.rotations[:, parent].reshape(3 * N, 3)
    Rm = (Rp @ frame.placement.rotation).reshape(N, 3, 3)
    pm = bk.translations[:, parent] + (Rp @ frame.placement.translation).reshape(N, 3)
    return Rm, pm


def serial_path(
    mech: Mechanism,
    params: ParameterSet,
    bk: BatchKinematics,
    values: np.ndarray | Linearisation,
    plan: JacobianPlan,
    out: np.ndarray | None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Measured rotations (N, 3, 3), positions (N, 3) and Jacobian (N, 6, n) of a chain.

    Args:
        mech: a mechanism without closures, at parameter ``values``.
        params: the n parameters.
        bk: the batched kinematics of the N configurations.
        values: (n,) parameter values, or their :class:`Linearisation`.
        plan: the ``(mech, params)`` plan.
        out: (N, 6, n) array of zeros to write the Jacobian into (allocated when None);
            only the columns of parameters that move the measured frame are written.

    Returns:
        The rotations, positions [m] and the Jacobian ``[p_world; rotation (local)]``
        per unit of each parameter.
    """
    N, n = bk.q.shape[0], len(params)
    Rm, pm = _measured_placement(mech, bk)
    J = np.zeros((N, 6, n)) if out is None else out
    lay = _layout(mech, params, values, plan)
    if not lay.runs:
        return Rm, pm, J
    chunk = max(32, BLOCK // lay.size)
    buf = _scratch_maps(lay.size, chunk)
    for start in range(0, N, chunk):
        rows = slice(start, start + chunk)
        S = _body_maps(bk, rows, lay, Rm[rows], pm[rows], buf)
        Jr = J[rows]
        for pos, cols, G in lay.runs:
            A = S[:, :, pos].transpose(0, 2, 1)  # (6 map rows, M, 6)
            if isinstance(cols, slice):
                np.matmul(A, G, out=Jr[:, :, cols].transpose(1, 0, 2))
            else:
                Jr[:, :, cols] = np.matmul(A, G).transpose(1, 0, 2)
    return Rm, pm, J
