"""The batched Newton core of the loop closing: residuals, factors and iterations.

:class:`BatchNewton` evaluates the closure residuals and Jacobians of N configurations
with :class:`~pincal.model.batch._batch.BatchModel` (numpy over the kinematic tree; every
point closure in one set of array operations), factors the N passive closure
Jacobians (:mod:`pincal.model.batch._block_solve` for square systems: one reduced system for
the shared joints, small blocks per leg; :class:`~pincal.model.batch._range_factor.RangeFactor`
for redundant rows or idle motion) and runs the Newton iterations of a chunk of poses.
:class:`~pincal.model.batch._batch_fk.BatchLoopSolver` builds the batched forward
kinematics on it.
"""

from __future__ import annotations

from collections.abc import Collection
from functools import cached_property
from typing import Literal, overload

import numpy as np

from pincal.errors import ShapeError
from pincal.model.batch._batch import BatchKinematics, BatchModel
from pincal.model.batch._batch_closures import (
    PointClosures,
    closure_jacobian_batch,
    closure_residual_batch,
)
from pincal.model.batch._block_solve import BlockSolver, DenseFactor, PassiveFactor
from pincal.model.batch._range_factor import RangeFactor
from pincal.model.loops import KinematicQueries, SolverOptions

__all__ = ["BatchNewton", "check_rows"]

#: Newton iterations of the batched solve before a row is handed to the pose-by-pose one
MAX_BATCH_ITERATIONS = 30
#: residual [m, rad] below which a converged row is not polished (round-off of
#: metre-sized machines: a further Newton step cannot halve it)
_ROUND_OFF = 1e-15


def check_rows(rows: np.ndarray, width: int, what: str) -> np.ndarray:
    """``rows`` as a float array (N, width).

    Raises:
        ShapeError: not numbers, or not of that shape.
    """
    try:
        out = np.atleast_2d(np.asarray(rows, dtype=float))
    except (TypeError, ValueError) as exc:
        raise ShapeError(f"{what} must be numbers: {exc}") from exc
    if out.ndim != 2 or out.shape[1] != width:
        raise ShapeError(f"{what} must have shape (N, {width}), got {np.shape(rows)}")
    return out


class BatchNewton:
    """Batched closure terms, passive factors and Newton iterations.

    Args:
        queries: the kinematic queries of the mechanism (model, closures, indices).
        options: the Newton settings.
        branch_block: the (rows, columns) branch block of the passive closure Jacobian
            (:attr:`~pincal.model.loops._branch.LoopSolver.branch_block`), None if none.
    """

    def __init__(
        self,
        queries: KinematicQueries,
        options: SolverOptions,
        branch_block: tuple[np.ndarray, np.ndarray] | None,
        template: tuple[BatchModel, Collection[int], Collection[int]] | None = None,
    ):
        self.queries, self.options, self.branch_block = queries, options, branch_block
        self._template = template
        self.model, self.name, self.closures = queries.model, queries.name, queries.closures
        self._free_v = queries.free_v
        self._point_closures_cache: dict[bytes, PointClosures] = {}

    @cached_property
    def batch_model(self) -> BatchModel:
        """The batched numpy kinematics of :attr:`model` (built once).

        With a ``template`` (the batched model of the mechanism this one's model was
        moved from, the joint ids and the frame indices that moved) only the moved
        placements are taken from :attr:`model`.
        """
        if self._template is not None:
            batch, joints, frames = self._template
            return batch.with_placements(self.model, joints, frames)
        return BatchModel(self.model)

    def kinematics_batch(self, qs: np.ndarray) -> BatchKinematics:
        """Joint placements and WORLD joint Jacobian of configurations ``qs`` (N, nq).

        Raises:
            ShapeError: ``qs`` is not (N, nq).
        """
        qs = check_rows(qs, self.model.nq, "configurations")
        if not self.batch_model.supported:
            raise ShapeError(  # pragma: no cover - every loader joint type is implemented
                f"mechanism {self.name!r} has a joint type the batched kinematics lacks"
            )
        return self.batch_model.kinematics(qs)

    def _point_closures(self, cols: np.ndarray) -> PointClosures:
        """The point closures on Jacobian columns ``cols`` (built once per column set)."""
        cache = self._point_closures_cache
        key = np.asarray(cols, dtype=np.int64).tobytes()
        if key not in cache:
            rows, frames, r0 = [], [], 0
            for fids, c in zip(self.queries.closure_fids, self.closures, strict=True):
                if c.is_point:
                    rows.append(r0)
                    frames.append(fids)
                r0 += c.size
            cache[key] = PointClosures(self.batch_model, frames, rows, cols)
        return cache[key]

    @cached_property
    def passive_solver(self) -> BlockSolver | None:
        """The block structure of the square passive closure Jacobian (None: dense)."""
        bm, free = self.batch_model, self._free_v
        blocks, support, r0 = [], [], 0
        for (a, b), c in zip(self.queries.closure_fids, self.closures, strict=True):
            moves = (bm.support_of_frame(a) | bm.support_of_frame(b))[free]
            blocks.append(np.arange(r0, r0 + c.size))
            support += [moves] * c.size
            r0 += c.size
        return BlockSolver.build(blocks, np.array(support)) if support else None

    def passive_factor(self, Jf: np.ndarray) -> PassiveFactor:
        """Factor passive closure Jacobians ``Jf`` (N, rows, k).

        Square ones by blocks where they reduce (else dense LU); non-square ones by
        QR (minimum-norm least squares, :class:`RangeFactor`).
        """
        if Jf.shape[1] != Jf.shape[2]:
            return RangeFactor.of(Jf, self.branch_block)
        solver = self.passive_solver
        return DenseFactor.of(Jf) if solver is None else solver.factor(Jf)

    def passive_steps(self, Jf: np.ndarray, r: np.ndarray) -> np.ndarray:
        """Newton steps ``−Jf⁺ r`` (N, k) of passive systems Jf (N, rows, k), r (N, rows).

        Square systems are solved with their factors (NaN rows where singular);
        non-square ones, of full rank min(rows, k) on the batched domain, by the normal
        equations of their smaller side (the minimum-norm least-squares step; its
        accuracy only sets the speed of convergence, the residual decides it).

        Raises:
            numpy.linalg.LinAlgError: a system is exactly singular.
        """
        if Jf.shape[1] == Jf.shape[2]:
            factor = self.passive_factor(Jf)
            step = -factor.solve(r[..., None])[..., 0]
            step[factor.singular] = np.nan
            return step
        Jt = np.swapaxes(Jf, 1, 2)
        if Jf.shape[1] < Jf.shape[2]:
            return -(Jt @ np.linalg.solve(Jf @ Jt, r[..., None]))[..., 0]
        return -np.linalg.solve(Jt @ Jf, Jt @ r[..., None])[..., 0]

    @overload
    def closure_terms_batch(
        self,
        bk: BatchKinematics,
        jacobian: Literal[True] = ...,
        columns: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray]: ...

    @overload
    def closure_terms_batch(
        self, bk: BatchKinematics, jacobian: bool, columns: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray | None]: ...

    def closure_terms_batch(
        self, bk: BatchKinematics, jacobian: bool = True, columns: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """Closure residuals (N, n_closure_rows) and Jacobians (N, n_closure_rows, nv).

        Args:
            bk: the batched kinematics.
            jacobian: also compute the Jacobians.
            columns: tangent dofs whose Jacobian columns to return (default all nv).
        """
        bm = self.batch_model
        N = bk.q.shape[0]
        cols = np.arange(self.model.nv) if columns is None else np.asarray(columns)
        if not self.closures:
            return np.zeros((N, 0)), (np.zeros((N, 0, cols.size)) if jacobian else None)
        sizes = [c.size for c in self.closures]
        r = np.empty((N, sum(sizes)))
        J = np.zeros((N, sum(sizes), cols.size)) if jacobian else None
        self._point_closures(cols).terms(bk, r, J)
        row = 0
        for (a, b), c in zip(self.queries.closure_fids, self.closures, strict=True):
            rows = slice(row, row + c.size)
            row += c.size
            if c.is_point:
                continue
            Ra, pa = bm.frame_placement(bk, a)
            Rb, pb = bm.frame_placement(bk, b)
            r[:, rows] = closure_residual_batch(c, Ra, pa, Rb, pb)
            if J is not None:
                Ja, Jb = bm.frame_jacobian(bk, a), bm.frame_jacobian(bk, b)
                J[:, rows] = closure_jacobian_batch(c, Ra, pa, Rb, pb, Ja, Jb)[:, :, cols]
        return r, J

    def _least_squares_steps(self, Jf: np.ndarray, r: np.ndarray) -> np.ndarray | None:
        """Newton steps (N, k) of redundant systems, None where one is exactly singular."""
        try:
            return self.passive_steps(Jf, r)
        except np.linalg.LinAlgError:
            return None

    def newton_chunk(
        self,
        Q: np.ndarray,
        out_R: np.ndarray,
        out_p: np.ndarray,
        out_J: np.ndarray,
        Jf_done: np.ndarray,
        max_iterations: int = MAX_BATCH_ITERATIONS,
        travel: np.ndarray | None = None,
        polish: bool = True,
        first: np.ndarray | None = None,
    ) -> np.ndarray:
        """Newton iterations of one chunk, in place: converged mask (N,).

        ``Q`` (N, nq) holds the start configurations (actuators set) and receives the
        solutions; the joint placements, joint Jacobian and passive closure Jacobian of
        each converged configuration are written into ``out_R``, ``out_p``, ``out_J``
        and ``Jf_done``. A converged row is polished as in the pose-by-pose solve: up
        to ``options.polish_steps`` more full steps, each kept only when it halves the
        largest residual (rows already at round-off, ≤ :data:`_ROUND_OFF`, stop).
        ``max_iterations`` bounds the Newton iterations; ``travel`` (N,), when given,
        receives the sum of the step norms of each row (≥ its distance moved), and
        ``first`` (N,), when given, the norm of its first step (the part of ``travel``
        a linearisation at the start predicts);
        ``polish=False`` stops at convergence (intermediate points of a continuation).
        With more closure rows than passive dofs and ``options.redundant_tol`` > 0 a row
        also converges as a least-squares closure (``_newton``): the part of its
        residual a step removes is ≤ ``tol`` and the remainder ≤ ``redundant_tol``.
        """
        bm, opt, free = self.batch_model, self.options, self._free_v
        N = Q.shape[0]
        active = np.ones(N, dtype=bool)
        done = np.zeros(N, dtype=bool)
        best = np.full(N, np.inf)  # largest residual of the recorded solution
        polished = np.zeros(N, dtype=int)
        prev = np.full(N, np.inf)
        Q_done = np.empty_like(Q)
        polish_steps = opt.polish_steps if polish else 0
        k = free.size
        least_squares = bool(opt.redundant_tol) and self.queries.n_closure_rows > k
        for it in range(max_iterations + polish_steps + 1):
            ia = np.nonzero(active)[0]
            if ia.size == 0:
                break
            bk = bm.kinematics(Q[ia])
            r, Jf = self.closure_terms_batch(bk, columns=free)
            rmax = np.max(np.abs(r), axis=1)
            norm = np.linalg.norm(r, axis=1)
            had = done[ia]  # polishing: a solution is recorded
            steps = self._least_squares_steps(Jf, r) if least_squares else None
            if steps is not None:  # least-squares closures: the removable part decides
                removable = np.max(np.abs((Jf @ steps[..., None])[..., 0]), axis=1)
                remainder = np.max(np.abs(r + (Jf @ steps[..., None])[..., 0]), axis=1)
                rmax = np.where(remainder <= (opt.redundant_tol or 0.0), removable, rmax)
            better = (rmax <= opt.tol) & (rmax < 0.5 * best[ia])
            ic = ia[better]
            done[ic], best[ic], Q_done[ic] = True, rmax[better], Q[ic]
            out_R[ic], out_p[ic], out_J[ic] = (
                bk.rotations[better],
                bk.translations[better],
                bk.jacobian[better],
            )
            Jf_done[ic] = Jf[better]
            back = ia[had & ~better]  # a polishing step that did not halve the residual
            Q[back] = Q_done[back]
            polish = better & (polished[ia] < polish_steps) & (rmax > _ROUND_OFF)
            descend = ~had & ~better & (norm < prev[ia])
            go = polish | descend
            active[ia[~go]] = False
            ig = ia[go]
            if ig.size == 0:
                continue
            polished[ia[polish]] += 1
            prev[ig] = norm[go]
            try:
                step = self.passive_steps(Jf[go], r[go]) if steps is None else steps[go]
            except np.linalg.LinAlgError:
                active[ig] = False
                Q[ig[done[ig]]] = Q_done[ig[done[ig]]]
                continue
            sn = np.linalg.norm(step, axis=1)
            step *= np.minimum(1.0, opt.max_step / np.maximum(sn, 1e-300))[:, None]
            bad = ~np.all(np.isfinite(step), axis=1)
            active[ig[bad]] = False
            DV = np.zeros((ig.size, self.model.nv))
            DV[:, free] = step
            Q[ig[~bad]] = bm.integrate(Q[ig[~bad]], DV[~bad])
            if travel is not None:
                travel[ig[~bad]] += np.minimum(sn, opt.max_step)[~bad]
            if first is not None and it == 0:
                first[ig[~bad]] = np.minimum(sn, opt.max_step)[~bad]
        Q[done] = Q_done[done]  # rows stopped after a polishing step: their solution
        return done
