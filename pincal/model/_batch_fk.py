"""Forward kinematics of many poses at once (batched Newton on the passive joints).

:class:`BatchTracking` is the part of :class:`~pincal.model.Mechanism` that closes the
loops for N actuator rows together, on :class:`~pincal.model._batch_newton.BatchNewton`
(closure terms, passive factors, Newton iterations in chunks of :data:`CHUNK` poses).
A pose is accepted when its residual is below ``options.tol`` and it is on home's
assembly branch (sign of det of the passive closure Jacobian or of its branch block,
from the same factors). Poses whose residual does not decrease, that leave the
branch, or whose condition bound comes near ``options.max_condition`` are handed to
the pose-by-pose solver (:meth:`configuration`: damped Newton, continuation, exact
singularity check), so results and errors are those of the pose-by-pose path.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np

from pincal.errors import ShapeError
from pincal.model._batch import BatchKinematics
from pincal.model._batch_closures import closure_jacobian_batch, closure_residual_batch
from pincal.model._batch_newton import BatchNewton

__all__ = ["BatchTracking", "closure_jacobian_batch", "closure_residual_batch"]

#: poses per chunk of the batched solves (temporaries of a chunk stay in the L2 cache)
CHUNK = 256


class BatchTracking(BatchNewton):
    """Batched loop closing (mixed into Mechanism)."""

    if TYPE_CHECKING:  # provided by Mechanism, which mixes this class in

        def configuration(
            self,
            q_act: np.ndarray,
            q_guess: np.ndarray | None = None,
            pose_index: int | None = None,
        ) -> np.ndarray: ...

    @property
    def batch_solvable(self) -> bool:
        """Whether the batched loop closing applies (else poses are closed one by one).

        It needs closures, the batched kinematics of every joint type, a passive
        closure Jacobian of full rank min(rows, passive dofs) at home, and a branch
        block regular there (``idle_branch`` ≠ 0): square systems, redundant closure
        rows and idle passive motion are all solved in batch.
        """
        rows, k = self.n_closure_rows, self._free_v.size
        return (
            bool(self.closures)
            and self.idle_branch != 0.0
            and self.batch_model.supported
            and self._rank_u == min(rows, k)
        )

    def _solve_batch(
        self, A: np.ndarray, Q0: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, BatchKinematics]:
        """Batched Newton: configurations (N, nq), accepted mask (N,), their kinematics.

        Rows not accepted (no decrease, no convergence, other branch, possibly
        singular) hold garbage and must be redone pose by pose. The Newton iterations
        run in chunks of :data:`CHUNK` poses (temporaries that stay in cache: cost
        linear in N), writing into the whole batch's arrays; the branch and condition
        checks then factor all the converged Jacobians at once.
        """
        N, nj, k = A.shape[0], self.model.njoints, self._free_v.size
        m = self.n_closure_rows
        Q = self._actuators_batch(Q0, A)
        R = np.empty((N, nj, 3, 3))
        p = np.empty((N, nj, 3))
        J = np.empty((N, 6, self.model.nv))
        Jf = np.empty((N, m, k))
        done = np.zeros(N, dtype=bool)
        for s in range(0, N, CHUNK):
            rows = slice(s, s + CHUNK)
            done[rows] = self._newton_chunk(Q[rows], R[rows], p[rows], J[rows], Jf[rows])
        Jf[~done] = np.eye(m, k)  # rows to be redone pose by pose: any full-rank matrix
        factor = self.passive_factor(Jf)
        with np.errstate(all="ignore"):
            # ‖Jf‖_F · (bound of ‖Jf⁻¹‖₂) ≥ cond₂: rows that might exceed the limit get
            # the exact check pose by pose
            cond = np.sqrt(np.sum(Jf**2, axis=(1, 2))) * factor.inverse_norm_bound()
        risky = ~np.isfinite(cond) | (cond > self.options.max_condition) | factor.singular
        ok = done & (factor.sign() == self.idle_branch) & ~risky
        return Q, ok, BatchKinematics(Q, R, p, J, Jf, factor)

    def try_configurations_batch(
        self, q_act_rows: np.ndarray, guesses: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray, BatchKinematics | None]:
        """Batched Newton only: configurations (N, nq), accepted mask (N,), kinematics.

        Rows not accepted (no convergence, other branch, possibly singular) hold no
        usable configuration: redo them with :meth:`configuration`. For a mechanism the
        batched solve does not apply to, nothing is accepted (kinematics None).
        """
        rows = self._check_rows(q_act_rows, len(self.actuated), "actuator rows")
        N = rows.shape[0]
        G = np.tile(self.q_home, (N, 1)) if guesses is None else guesses
        G = self._check_rows(G, self.model.nq, "guesses")
        if not self.closures and self.batch_model.supported:
            Q = self._actuators_batch(G, rows)
            return Q, np.ones(N, dtype=bool), self.batch_model.kinematics(Q)
        if not self.batch_solvable:
            return np.array(G), np.zeros(N, dtype=bool), None
        return self._solve_batch(rows, G)

    def configurations_batch(
        self, q_act_rows: np.ndarray, guesses: np.ndarray | None = None
    ) -> tuple[np.ndarray, BatchKinematics | None]:
        """Closed configurations (N, nq) on home's branch and their kinematics.

        Args:
            q_act_rows: (N, n_act) actuator values [m, rad].
            guesses: (N, nq) start configurations (default: home for the batched solve;
                rows redone pose by pose start from the previous row's solution).

        Returns:
            The configurations, and their :class:`BatchKinematics` (None when the
            batched kinematics does not apply to this mechanism).

        Raises:
            ConvergenceError, SingularConfigurationError: as :meth:`configuration`,
                naming the pose index.
        """
        rows = self._check_rows(q_act_rows, len(self.actuated), "actuator rows")
        N = rows.shape[0]
        G = None if guesses is None else self._check_rows(guesses, self.model.nq, "guesses")
        if G is not None and G.shape[0] != N:
            raise ShapeError(f"guesses must have {N} rows (one per actuator row), got {len(G)}")
        if not self.closures:
            out = self._actuators_batch(np.tile(self.q_home, (N, 1)) if G is None else G, rows)
            return out, (self.batch_model.kinematics(out) if self.batch_model.supported else None)
        if not self.batch_solvable:
            out = np.empty((N, self.model.nq))
            for i, row in enumerate(rows):
                guess = G[i] if G is not None else (out[i - 1] if i else self.q_home)
                out[i] = self.configuration(row, guess, pose_index=i)
            bk = self.batch_model.kinematics(out) if self.batch_model.supported else None
            return out, bk
        start = np.tile(self.q_home, (N, 1)) if G is None else G
        Q, ok, bk = self._solve_batch(rows, start)
        for j in np.nonzero(~ok)[0]:
            guess = G[j] if G is not None else (Q[j - 1] if j else self.q_home)
            Q[j] = self.configuration(rows[j], guess, pose_index=int(j))
        redo = np.nonzero(~ok)[0]
        if redo.size:
            fix = self.batch_model.kinematics(Q[redo])
            bk.rotations[redo], bk.translations[redo] = fix.rotations, fix.translations
            bk.jacobian[redo] = fix.jacobian
            if bk.closure_jacobian is not None:  # regular there: configuration() checked it
                bk.closure_jacobian[redo] = self.closure_terms_batch(fix, columns=self._free_v)[1]
                bk = dataclasses.replace(
                    bk, closure_factor=self.passive_factor(bk.closure_jacobian)
                )
        return Q, bk
