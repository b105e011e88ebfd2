"""Closure residuals and Jacobians of N poses (arrays (N, …)).

:func:`closure_residual_batch` / :func:`closure_jacobian_batch` evaluate one closure
from its frames' placements and local twists. :class:`PointClosures` evaluates every
point closure (``p_b = p_a`` in world axes, the common ball-joint cut) of a mechanism
in one set of array operations, on the columns that can be non-zero only.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from pincal.model.batch._batch import BatchKinematics, BatchModel, cross_cols, mm, mv
from pincal.model.batch._batch_ops import jlog3_batch, log3_batch
from pincal.model.files import Closure

__all__ = ["PointClosures", "closure_jacobian_batch", "closure_residual_batch"]


def closure_residual_batch(
    c: Closure, Ra: np.ndarray, pa: np.ndarray, Rb: np.ndarray, pb: np.ndarray
) -> np.ndarray:
    """Residuals (N, c.size) of closure ``c`` from frame placements (N, 3, 3), (N, 3)."""
    if c.is_point:
        return pb - pa
    Rat = np.swapaxes(Ra, 1, 2)
    full = [mv(Rat, pb - pa)]
    if c.components[-1] >= 3:
        full.append(log3_batch(mm(Rat, Rb)))
    return np.concatenate(full, axis=1)[:, list(c.components)]


def closure_jacobian_batch(
    c: Closure,
    Ra: np.ndarray,
    pa: np.ndarray,
    Rb: np.ndarray,
    pb: np.ndarray,
    Ta: np.ndarray,
    Tb: np.ndarray,
) -> np.ndarray:
    """(N, c.size, n) derivative of :func:`closure_residual_batch` given local twists.

    Args:
        c: the closure.
        Ra: (N, 3, 3) world rotations of the closure's frame a.
        pa: (N, 3) world positions of frame a [m].
        Rb: (N, 3, 3) world rotations of the closure's frame b.
        pb: (N, 3) world positions of frame b [m].
        Ta: (N, 6, n) local twists ``[v; ω]`` of frame a per unit of each of n
            variables (LOCAL frame Jacobians or parameter sensitivities) [m, rad].
        Tb: (N, 6, n) local twists ``[v; ω]`` of frame b, as ``Ta``.
    """
    if c.is_point:
        return mm(Rb, Tb[:, :3]) - mm(Ra, Ta[:, :3])
    Rat = np.swapaxes(Ra, 1, 2)
    t = mv(Rat, pb - pa)
    Rab = mm(Rat, Rb)
    blocks = [cross_cols(t[:, :, None], Ta[:, 3:]) + mm(Rab, Tb[:, :3]) - Ta[:, :3]]
    if c.components[-1] >= 3:
        dw = Tb[:, 3:] - mm(np.swapaxes(Rab, 1, 2), Ta[:, 3:])
        blocks.append(jlog3_batch(log3_batch(Rab)) @ dw)
    return np.concatenate(blocks, axis=1)[:, list(c.components)]


class PointClosures:
    """Every point closure of a mechanism, evaluated together.

    Args:
        bm: the batched kinematics of the model.
        frames: (frame a, frame b) ids of each point closure (C closures).
        rows: (C,) first row of each closure in the closure residual vector.
        columns: (k,) the tangent dofs whose Jacobian columns are wanted.
    """

    def __init__(
        self,
        bm: BatchModel,
        frames: Sequence[tuple[int, int]],
        rows: Sequence[int],
        columns: np.ndarray,
    ):
        self.bm = bm
        cols = np.asarray(columns, dtype=int)
        fa = np.array([a for a, _ in frames], dtype=int)
        fb = np.array([b for _, b in frames], dtype=int)
        first = np.asarray(rows, dtype=int)
        ma = np.array([bm.support_of_frame(a)[cols] for a in fa]).reshape(-1, cols.size)
        mb = np.array([bm.support_of_frame(b)[cols] for b in fb]).reshape(-1, cols.size)
        # per closure, the columns that move frame a or b; a closure no column moves has
        # zero Jacobian rows (the caller's J starts at zero) and is left out of the scatter
        touched = [np.nonzero(x | y)[0] for x, y in zip(ma, mb, strict=True)]
        moved = np.array([t.size > 0 for t in touched], dtype=bool).reshape(-1)
        #: all closures' frames and rows (residuals), (C,) and (C, 3)
        self.fa, self.fb = fa, fb
        self.rows = first[:, None] + np.arange(3)
        # the moved closures' columns, padded to a common width w by repeating the first
        # (written twice with the same value)
        kept = [t for t in touched if t.size]
        w = max((t.size for t in kept), default=0)
        local = np.array([np.pad(t, (0, w - t.size), mode="edge") for t in kept], dtype=int)
        local = local.reshape(len(kept), w)
        self.moved = moved
        self.ma = np.take_along_axis(ma[moved], local, axis=1).astype(float)
        self.mb = np.take_along_axis(mb[moved], local, axis=1).astype(float)
        self.dofs = cols[local]  # (C', w) tangent dof of each column of a moved closure
        self._ma, self._mb = self.ma[:, :, None, None], self.mb[:, :, None, None]
        self._sign = self._mb - self._ma
        #: (3, C', w) flat index of each entry in a (rows × len(columns)) Jacobian
        self.flat = self.rows[moved].T[:, :, None] * cols.size + local[None]

    def terms(self, bk: BatchKinematics, r: np.ndarray, J: np.ndarray | None) -> None:
        """Write residuals into ``r`` (N, rows) and Jacobians into ``J`` (N, rows, k).

        A point p on a moving body has world velocity ``v_o + ω × p``; the residual
        ``p_b − p_a`` moves by the columns of the dofs under b minus those under a.
        """
        pa = self.bm.frame_positions(bk, self.fa)  # (N, C, 3)
        pb = self.bm.frame_positions(bk, self.fb)
        r[:, self.rows] = pb - pa
        if J is None or self.flat.size == 0:
            return
        pa, pb = pa[:, self.moved], pb[:, self.moved]
        # poses last (arrays (C, w, 3, N)): the masks broadcast over long contiguous rows
        G = np.ascontiguousarray(np.transpose(bk.jacobian, (2, 1, 0)))[self.dofs]  # (C, w, 6, N)
        Jw = G[:, :, 3:]
        P = (
            np.transpose(pb, (1, 2, 0))[:, None] * self._mb
            - np.transpose(pa, (1, 2, 0))[:, None] * self._ma
        )  # (C, w, 3, N)
        out = np.empty_like(P)
        out[:, :, 0] = Jw[:, :, 1] * P[:, :, 2] - Jw[:, :, 2] * P[:, :, 1]
        out[:, :, 1] = Jw[:, :, 2] * P[:, :, 0] - Jw[:, :, 0] * P[:, :, 2]
        out[:, :, 2] = Jw[:, :, 0] * P[:, :, 1] - Jw[:, :, 1] * P[:, :, 0]
        out += G[:, :, :3] * self._sign
        J.reshape(J.shape[0], -1)[:, self.flat] = np.transpose(out, (3, 2, 0, 1))
