"""Forward kinematics of many poses at once (batched Newton on the passive joints).

:class:`BatchLoopSolver` closes the loops for N actuator rows together, on
:class:`~pincal.model.batch._batch_newton.BatchNewton`
(closure terms, passive factors, Newton iterations in chunks of :data:`CHUNK` poses).
A direct solve is a continuation step over the whole path and must stay near its
prediction (a bare Newton from a far start can land on another assembly mode of the
same sign): from home it starts at the first-order (tangent) prediction and its Newton
steps add up to at most a quarter of the predicted passive motion; from warm starts
(guesses) the Newton's own first step, at the guess with the actuators set, is the
prediction, and the steps after it add up to at most a quarter of it (a contraction
test, free: it needs no Jacobian at the guess). A pose is accepted when
its residual is below ``options.tol`` and it is on home's
assembly branch (sign of det of the passive closure Jacobian or of its branch block,
from the same factors). Poses whose residual does not decrease, that leave the
branch, or whose condition bound comes near ``options.max_condition`` are handed to
the pose-by-pose solver (:meth:`~pincal.model.loops._branch.LoopSolver.configuration`:
damped Newton, continuation, exact singularity check), so results and errors are
those of the pose-by-pose path.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from pincal.errors import ConvergenceError, ShapeError
from pincal.model.batch._batch import BatchKinematics
from pincal.model.batch._batch_closures import closure_jacobian_batch, closure_residual_batch
from pincal.model.batch._batch_newton import BatchNewton, check_rows
from pincal.model.batch._block_solve import PassiveFactor
from pincal.model.loops import CORRECTOR_ITERATIONS, MIN_STEP, LoopSolver

__all__ = ["BatchLoopSolver", "closure_jacobian_batch", "closure_residual_batch"]

#: poses per chunk of the batched solves (temporaries of a chunk stay in the L2 cache)
CHUNK = 256
#: fewest rows a batched continuation step is run for: a step costs about the same
#: for 1 row as for 50 (array-call overhead; 2–3 ms on the test machines), while the
#: pose-by-pose solver closes such a row in 2–10 ms; fewer rows go pose by pose
_MIN_CONTINUATION_ROWS = 16


class BatchLoopSolver:
    """Batched loop closing on home's branch, falling back on the pose-by-pose solver.

    Args:
        kernels: the batched closure terms, factors and Newton iterations.
        loop: the pose-by-pose solver (home, its branch, the fallback for rows the
            batched solve does not accept).
    """

    def __init__(self, kernels: BatchNewton, loop: LoopSolver):
        self.kernels, self.loop = kernels, loop
        self.queries, self.options = loop.queries, loop.options
        self.model, self.closures = loop.model, loop.closures
        self.q_home, self.idle_branch = loop.q_home, loop.idle_branch
        self._free_v = loop.queries.free_v

    @property
    def batch_solvable(self) -> bool:
        """Whether the batched loop closing applies (else poses are closed one by one).

        It needs closures, the batched kinematics of every joint type, a passive
        closure Jacobian of full rank min(rows, passive dofs) at home, and a branch
        block regular there (``idle_branch`` ≠ 0): square systems, redundant closure
        rows and idle passive motion are all solved in batch.
        """
        rows, k = self.queries.n_closure_rows, self._free_v.size
        return (
            bool(self.closures)
            and self.idle_branch != 0.0
            and self.kernels.batch_model.supported
            and self.loop.passive_rank == min(rows, k)
        )

    def _continue_batch(
        self, A: np.ndarray, Q0: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Start configurations for the rows a direct batched solve missed.

        The pose-by-pose continuation (``_branch``), all rows at once: from the closed
        configurations ``Q0``, each row follows the straight actuator path to its row
        of ``A`` (n, n_act) in steps that double after a success and halve after a
        failure, down to 1/4096 of the path. A step is predicted to first order
        (passive motion ``−Jf⁺ Ja Δa``), corrected by a short batched Newton, and kept
        when the corrector converges on home's branch near the prediction (its steps
        add up to at most a quarter of the predicted motion). Each row's path is its
        own: the result does not depend on the other rows of the batch. When fewer
        than :data:`_MIN_CONTINUATION_ROWS` rows are still on the way, they stop
        (unreached: the pose-by-pose solver closes them faster).

        Returns:
            The configurations reached at the path ends (r, nq), the mask (n,) of the r
            rows that reached it, and the mask (n,) of the rows given up on (step below
            1/4096 of the path: the pose-by-pose continuation's own failure).
        """
        n, free = A.shape[0], self._free_v
        a0 = self.queries.actuator_values_batch(Q0)
        t, h = np.zeros(n), np.full(n, 0.25)
        Q = np.array(Q0)
        kin = self.kernels.batch_model.kinematics(Q)  # of each row's last closed configuration
        R, p, J = kin.rotations, kin.translations, kin.jacobian
        alive = np.ones(n, dtype=bool)
        gave_up = np.zeros(n, dtype=bool)
        while True:
            i = np.nonzero(alive & (t < 1.0))[0]
            if i.size < _MIN_CONTINUATION_ROWS:  # a short tail: faster pose by pose
                alive[i] = False
                break
            h[i] = np.minimum(h[i], 1.0 - t[i])
            a = a0[i] + (t[i] + h[i])[:, None] * (A[i] - a0[i])
            try:
                cand, moved = self._predict_batch(BatchKinematics(Q[i], R[i], p[i], J[i]), a)
            except np.linalg.LinAlgError:  # an exactly singular row: all to the fallback
                alive[i] = False
                break
            travel = np.zeros(i.size)
            Rc, pc, Jjc = np.empty_like(R[i]), np.empty_like(p[i]), np.empty_like(J[i])
            Jf = np.empty((i.size, self.queries.n_closure_rows, free.size))
            conv = self.kernels.newton_chunk(
                cand,
                Rc,
                pc,
                Jjc,
                Jf,
                max_iterations=CORRECTOR_ITERATIONS,
                travel=travel,
                polish=False,
            )
            Jf[~conv] = np.eye(*Jf.shape[1:])
            ok = conv & (self.kernels.passive_factor(Jf).sign() == self.idle_branch)
            ok &= travel <= 0.25 * moved + 1e-7
            Q[i[ok]], t[i[ok]] = cand[ok], t[i[ok]] + h[i[ok]]
            R[i[ok]], p[i[ok]], J[i[ok]] = Rc[ok], pc[ok], Jjc[ok]
            h[i] = np.where(ok, 2.0 * h[i], 0.5 * h[i])
            gave_up[i[h[i] < MIN_STEP]] = True
            alive &= ~gave_up
        reached = alive & (t >= 1.0)
        return self.queries.actuators_batch(Q[reached], A[reached]), reached, gave_up

    def _predict_batch(self, bk: BatchKinematics, a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """First-order predictions (n, nq) and their passive motion norms (n,).

        From the configurations of ``bk`` to the actuator rows ``a`` (n, n_act).

        Raises:
            numpy.linalg.LinAlgError: a passive system is exactly singular.
        """
        free, act = self._free_v, self.queries.act_v_arr
        # two calls: the closure Jacobian's cost grows with the columns each closure's
        # frames depend on, which the passive and the actuated ones together make more
        r, Jf = self.kernels.closure_terms_batch(bk, columns=free)
        Ja = self.kernels.closure_terms_batch(bk, columns=act)[1]
        da = a - self.queries.actuator_values_batch(bk.q)
        rate = (Ja @ da[..., None])[..., 0] + r  # closing unclosed starts too
        return self._predicted(bk.q, a, self.kernels.passive_steps(Jf, rate))

    def _predicted(
        self, G: np.ndarray, A: np.ndarray, step: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Configurations G (n, nq) moved by passive steps (n, k), actuators A; norms (n,)."""
        DV = np.zeros((A.shape[0], self.model.nv))
        DV[:, self._free_v] = step
        cand = self.queries.actuators_batch(self.kernels.batch_model.integrate(G, DV), A)
        return cand, np.linalg.norm(step, axis=1)

    def _predicted_starts(self, A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Start configurations (N, nq) of the direct solves from home to ``A`` (N, n_act).

        The first-order prediction from home (a continuation step over the whole path),
        with the norms (N,) of the predicted passive motions. Its step ``−Jf⁺ (Ja Δa +
        r)`` is linear in Δa: home's system is solved once, for the n_act columns of
        ``Ja`` and for ``r``. Where it is singular the rows start at home with the
        actuators set (and motion 0: they must close right there).
        """
        free, act = self._free_v, self.queries.act_v_arr
        G = np.broadcast_to(self.q_home, (A.shape[0], self.model.nq))
        kin = self.kernels.batch_model.kinematics(self.q_home[None])
        r, Jf = self.kernels.closure_terms_batch(kin, columns=free)
        Ja = self.kernels.closure_terms_batch(kin, columns=act)[1]
        rhs = np.vstack([Ja[0].T, r])  # (n_act + 1, rows)
        try:
            unit = self.kernels.passive_steps(np.broadcast_to(Jf, (len(rhs), *Jf.shape[1:])), rhs)
        except np.linalg.LinAlgError:
            return self.queries.actuators_batch(G, A), np.zeros(A.shape[0])
        da = A - self.queries.actuator_values_batch(self.q_home[None])
        cand, moved = self._predicted(G, A, da @ unit[: act.size] + unit[act.size])
        bad = ~np.all(np.isfinite(cand), axis=1) | ~np.isfinite(moved)
        cand[bad], moved[bad] = self.queries.actuators_batch(G[bad], A[bad]), 0.0
        return cand, moved

    def close_chunks(
        self,
        Q: np.ndarray,
        R: np.ndarray,
        p: np.ndarray,
        J: np.ndarray,
        Jf: np.ndarray,
        travel: np.ndarray | None = None,
        first: np.ndarray | None = None,
    ) -> np.ndarray:
        """Batched Newton in chunks of :data:`CHUNK` rows, in place: converged mask (N,).

        ``travel`` (N,), when given, receives the sum of each row's step norms, and
        ``first`` (N,) the norm of its first step.
        """
        done = np.zeros(Q.shape[0], dtype=bool)
        for s in range(0, Q.shape[0], CHUNK):
            rows = slice(s, s + CHUNK)
            done[rows] = self.kernels.newton_chunk(
                Q[rows],
                R[rows],
                p[rows],
                J[rows],
                Jf[rows],
                travel=None if travel is None else travel[rows],
                first=None if first is None else first[rows],
            )
        return done

    def accept(
        self, Jf: np.ndarray, done: np.ndarray
    ) -> tuple[PassiveFactor, np.ndarray, np.ndarray]:
        """Factors of ``Jf`` (N, rows, k), accepted mask (N,) and possibly singular mask (N,).

        A converged row is accepted on home's branch when its condition bound
        ``‖Jf‖_F · (bound of ‖Jf⁺‖₂) ≥ cond₂`` is within ``options.max_condition``;
        the others get the exact check pose by pose. Rows not converged are given an
        identity stand-in in ``Jf`` (any full-rank matrix).
        """
        Jf[~done] = np.eye(*Jf.shape[1:])
        factor = self.kernels.passive_factor(Jf)
        with np.errstate(all="ignore"):
            cond = np.sqrt(np.sum(Jf**2, axis=(1, 2))) * factor.inverse_norm_bound()
        risky = ~np.isfinite(cond) | (cond > self.options.max_condition) | factor.singular
        return factor, done & (factor.sign() == self.idle_branch) & ~risky, risky

    def _solve_batch(
        self, A: np.ndarray, Q0: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, BatchKinematics, np.ndarray]:
        """Batched Newton: configurations, accepted rows, kinematics, rows given up on.

        Returns the configurations (N, nq), the accepted mask (N,), their kinematics and
        the mask (N,) of rows the batched continuation gave up on. Rows not accepted
        (no decrease, no convergence, other branch, possibly singular) hold garbage and
        must be redone pose by pose. The Newton iterations run in chunks of
        :data:`CHUNK` poses (temporaries that stay in cache: cost linear in N), writing
        into the whole batch's arrays; the branch and condition checks then factor all
        the converged Jacobians at once.
        """
        N, nj, k = A.shape[0], self.model.njoints, self._free_v.size
        m = self.queries.n_closure_rows
        moved = None  # from guesses: the Newton's first step there is the prediction
        if np.array_equal(Q0, np.broadcast_to(self.q_home, Q0.shape)):
            Q, moved = self._predicted_starts(A)
        else:
            Q = self.queries.actuators_batch(Q0, A)
        R = np.empty((N, nj, 3, 3))
        p = np.empty((N, nj, 3))
        J = np.empty((N, 6, self.model.nv))
        Jf = np.empty((N, m, k))
        travel, first = np.zeros(N), np.zeros(N)
        done = self.close_chunks(Q, R, p, J, Jf, travel, first)
        # a direct solve is a continuation step over the whole path: it must stay near
        # its prediction (else it may have landed on another mode with the same sign)
        if moved is None:
            near = travel - first <= 0.25 * first + 1e-7
        else:
            near = travel <= 0.25 * moved + 1e-7
        factor, signed, risky = self.accept(Jf, done)  # signed: the last resort
        done &= near
        ok = signed & near
        # not closed or on another branch (not merely near a singularity): continuation
        retry = np.nonzero(~ok & ~(done & risky))[0]
        hopeless = np.zeros(N, dtype=bool)
        if retry.size >= _MIN_CONTINUATION_ROWS:
            home = np.tile(self.q_home, (retry.size, 1))
            Qc, reached, gave_up = self._continue_batch(A[retry], home)
            hopeless[retry[gave_up]] = True
            hopeless &= ~signed  # the pose-by-pose solver falls back on those
            idx = retry[reached]
            if idx.size:
                Rc, pc, Jc, Jfc = R[idx], p[idx], J[idx], Jf[idx]
                done[idx] = self.close_chunks(Qc, Rc, pc, Jc, Jfc)
                Q[idx], R[idx], p[idx], J[idx], Jf[idx] = Qc, Rc, pc, Jc, Jfc
                factor, ok, _ = self.accept(Jf, done)
        return Q, ok, BatchKinematics(Q, R, p, J, Jf, factor), hopeless

    def try_configurations_batch(
        self, q_act_rows: np.ndarray, guesses: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray, BatchKinematics | None]:
        """Batched Newton only: configurations (N, nq), accepted mask (N,), kinematics.

        Rows not accepted (no convergence, other branch, possibly singular) hold no
        usable configuration: redo them with :meth:`configuration`. For a mechanism the
        batched solve does not apply to, nothing is accepted (kinematics None).
        """
        rows = check_rows(q_act_rows, len(self.queries.actuated), "actuator rows")
        N = rows.shape[0]
        G = np.tile(self.q_home, (N, 1)) if guesses is None else guesses
        G = check_rows(G, self.model.nq, "guesses")
        if not self.closures and self.kernels.batch_model.supported:
            Q = self.queries.actuators_batch(G, rows)
            return Q, np.ones(N, dtype=bool), self.kernels.batch_model.kinematics(Q)
        if not self.batch_solvable:
            return np.array(G), np.zeros(N, dtype=bool), None
        return self._solve_batch(rows, G)[:3]

    def closable_batch(self, q_act_rows: np.ndarray) -> np.ndarray:
        """Whether each actuator row (N, n_act) closes on home's branch (N,) bool.

        The answer of :meth:`configuration` (no error: closed on home's branch away
        from singularities), decided in batch where possible: rows the batched solve
        closes, and rows its continuation gives up on by the pose-by-pose criterion
        (a step below 1/4096 of the path); the others are tried pose by pose.
        """
        rows = check_rows(q_act_rows, len(self.queries.actuated), "actuator rows")
        ok = np.zeros(rows.shape[0], dtype=bool)
        hopeless = np.zeros_like(ok)
        if not self.closures:
            ok[:] = True
        elif self.batch_solvable:
            _, ok, _, hopeless = self._solve_batch(rows, np.tile(self.q_home, (len(rows), 1)))
        for j in np.nonzero(~ok & ~hopeless)[0]:
            try:
                self.loop.configuration(rows[j])
                ok[j] = True
            except ConvergenceError:
                pass
        return ok

    def configurations_batch(
        self, q_act_rows: np.ndarray, guesses: np.ndarray | None = None
    ) -> tuple[np.ndarray, BatchKinematics | None]:
        """Closed configurations (N, nq) on home's branch and their kinematics.

        Args:
            q_act_rows: (N, n_act) actuator values [m, rad].
            guesses: (N, nq) start configurations (default: home, for the batched solve
                and for the rows redone pose by pose: a neighbouring row's solution is
                no safe start — on a mechanism of several loops a direct solve from it
                can close on another assembly mode with the same branch sign, e.g. the
                2-RSU ankle's foot turned over at wide motor angles).

        Returns:
            The configurations, and their :class:`BatchKinematics` (None when the
            batched kinematics does not apply to this mechanism).

        Raises:
            ConvergenceError, SingularConfigurationError: as :meth:`configuration`,
                naming the pose index.
        """
        rows = check_rows(q_act_rows, len(self.queries.actuated), "actuator rows")
        N = rows.shape[0]
        G = None if guesses is None else check_rows(guesses, self.model.nq, "guesses")
        if G is not None and G.shape[0] != N:
            raise ShapeError(f"guesses must have {N} rows (one per actuator row), got {len(G)}")
        if not self.closures:
            out = self.queries.actuators_batch(
                np.tile(self.q_home, (N, 1)) if G is None else G, rows
            )
            return out, (
                self.kernels.batch_model.kinematics(out)
                if self.kernels.batch_model.supported
                else None
            )
        if not self.batch_solvable:
            out = np.empty((N, self.model.nq))
            for i, row in enumerate(rows):
                guess = G[i] if G is not None else (out[i - 1] if i else self.q_home)
                out[i] = self.loop.configuration(row, guess, pose_index=i)
            bk = (
                self.kernels.batch_model.kinematics(out)
                if self.kernels.batch_model.supported
                else None
            )
            return out, bk
        start = np.tile(self.q_home, (N, 1)) if G is None else G
        Q, ok, bk, _ = self._solve_batch(rows, start)
        for j in np.nonzero(~ok)[0]:  # from home (or the row's guess), as configuration()
            guess = G[j] if G is not None else self.q_home
            Q[j] = self.loop.configuration(rows[j], guess, pose_index=int(j))
        redo = np.nonzero(~ok)[0]
        if redo.size:
            fix = self.kernels.batch_model.kinematics(Q[redo])
            bk.rotations[redo], bk.translations[redo] = fix.rotations, fix.translations
            bk.jacobian[redo] = fix.jacobian
            if bk.closure_jacobian is not None:  # regular there: configuration() checked it
                bk.closure_jacobian[redo] = self.kernels.closure_terms_batch(
                    fix, columns=self._free_v
                )[1]
                bk = dataclasses.replace(
                    bk, closure_factor=self.kernels.passive_factor(bk.closure_jacobian)
                )
        return Q, bk
