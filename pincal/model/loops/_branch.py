"""Forward kinematics that stays on the assembly mode (branch) of the home configuration.

A closed loop usually closes in several ways for the same actuator values (knees up or
down). A Newton solve warm-started from an arbitrary configuration can land on any of
them. Here a solution is accepted only when it is on the branch of ``q_home``:

* where the passive closure Jacobian is square, the sign of its determinant must equal
  the sign at home (it changes exactly when a passive singularity is crossed);
* where it is not square — redundant closure rows (a ``3d``/``6d`` closure of a planar
  loop) or idle passive motion (e.g. the spin of an RSSR coupler about its own axis:
  it moves nothing the closures or the measured frame see) — a square block of its
  rank is checked instead: the rows of a row-pivoted QR at home, and the columns left
  when those carrying most of the idle motion at home are dropped (column-pivoted QR
  of the home nullspace). Its sign is ``idle_branch``; ``home_branch`` stays 0 for
  such mechanisms;
* a direct solve is a predictor-corrector step over the whole path (first-order
  passive motion, then Newton) kept only on home's branch *and* near its prediction
  (correction ≤ a quarter of the predicted motion): a bare Newton from a far start can
  land on another assembly mode with the same sign (a Delta with two legs flipped);
* a direct solve from the start configuration that fails these tests is followed by a
  direct solve from home (a warm start never loses a pose the solve from home closes),
  then by a continuation: a straight path in actuator space from the start (then from home),
  in steps that halve until each step converges, keeps the sign and moves the passive
  joints as the first-order predictor says. Its corrector starts next to the solution
  when the step is good, so it gets a short budget (a few iterations, a few line-search
  halvings): a corrector that needs more — the step runs past the edge of the workspace,
  where the loops have no assembly — fails fast and the step is halved, instead of
  creeping toward a non-zero minimum of the residual for the full Newton budget.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin

from pincal.errors import ConvergenceError, SingularConfigurationError
from pincal.model.loops._assembly import Extra, closure_newton, say_length
from pincal.model.loops._kinematics import KinematicQueries
from pincal.model.loops._newton import Solution, SolverOptions

__all__ = ["LoopSolver", "corrector_options"]

MIN_STEP = 1.0 / 4096  # smallest continuation step, as a fraction of the path
#: corrector budget of one continuation step: converging correctors take <= 9 iterations
#: and (almost) never backtrack on the bundled machines
CORRECTOR_ITERATIONS = 12
_CORRECTOR_BACKTRACKS = 4


def corrector_options(options: SolverOptions) -> SolverOptions:
    """The short-budget Newton settings of a continuation corrector (same tolerances)."""
    return dataclasses.replace(
        options,
        max_iterations=min(options.max_iterations, CORRECTOR_ITERATIONS),
        max_backtracks=min(options.max_backtracks, _CORRECTOR_BACKTRACKS),
    )


class LoopSolver:
    """Pose-by-pose loop closing on the assembly branch of home.

    Args:
        queries: the kinematic queries of the mechanism.
        options: the Newton settings.
        q_home: (nq,) the assembled home configuration.
        passive_rank: rank of the passive closure Jacobian at home
            (:attr:`~pincal.model.loops._assembly.Mobility.passive_rank`).

    Attributes:
        home_branch: sign of det of the passive closure Jacobian at home (0 where it is
            not square).
        idle_branch: the sign of its branch block (the square block of rank rows and
            non-idle columns; = ``home_branch`` where the Jacobian is square; 0: no
            branch is checked).
        branch_block: (rows, columns) of that block, None when there is none.
        home_notes: inverse kinematics' verdict from home per set of imposed components
            (what it says if Newton stalls there; :mod:`pincal.model.loops._inverse`), kept.
    """

    def __init__(
        self,
        queries: KinematicQueries,
        options: SolverOptions,
        q_home: np.ndarray,
        passive_rank: int,
    ):
        self.queries, self.options, self.q_home = queries, options, q_home
        self.model, self.closures = queries.model, queries.closures
        self.passive_rank = passive_rank
        self._free_v = queries.free_v
        n, rows, r = self._free_v.size, queries.n_closure_rows, passive_rank
        square = bool(self.closures and rows == n and r == n)
        self.branch_block: tuple[np.ndarray, np.ndarray] | None = None
        if square:
            self.branch_block = (np.arange(n), np.arange(n))
        elif self.closures and r > 0:
            self.branch_block = self._reduced_block()
        sign = self.branch_sign(q_home)
        self.home_branch = sign if square else 0.0
        self.idle_branch = sign
        self.home_notes: dict[tuple[str, ...], str] = {}

    def newton(
        self,
        q0: np.ndarray,
        free: np.ndarray,
        extra: Extra | None = None,
        options: SolverOptions | None = None,
    ) -> Solution:
        """Damped Newton on the closures (+ ``extra``) over tangent dofs ``free``.

        ``options`` replaces :attr:`options` for this solve (see
        :func:`~pincal.model.loops._assembly.closure_newton`).
        """
        return closure_newton(self.queries, q0, free, options or self.options, extra)

    def _branch_det_sign(self, Jf: np.ndarray) -> float:
        """Sign of det of the branch block of a passive closure Jacobian (rows, n_free)."""
        if self.branch_block is None:
            return 0.0
        rows, cols = self.branch_block
        return float(np.sign(np.linalg.det(Jf[np.ix_(rows, cols)])))

    def branch_sign(self, q: np.ndarray) -> float:
        """Sign of det of the (reduced) passive closure Jacobian at q, 0 if undefined."""
        if self.branch_block is None:
            return 0.0
        return self._branch_det_sign(self.queries.closure_jacobian(q)[:, self._free_v])

    def _reduced_block(self) -> tuple[np.ndarray, np.ndarray] | None:
        """Independent rows and non-idle columns of the passive closure Jacobian at home.

        None when that square block is not well-conditioned at home (then no branch is
        checked, as before).
        """
        import scipy.linalg  # here: importing pincal must not load scipy

        J = self.queries.closure_jacobian(self.q_home)[:, self._free_v]
        r = self.passive_rank
        _, _, row_piv = scipy.linalg.qr(J.T, pivoting=True)
        rows = np.sort(row_piv[:r])
        _, _, Vt = np.linalg.svd(J[rows])
        null = Vt[r:]  # (idle, n): the idle directions at home
        cols = np.arange(J.shape[1])
        if null.shape[0]:
            _, _, piv = scipy.linalg.qr(null, pivoting=True)
            cols = np.sort(piv[null.shape[0] :])
        s = np.linalg.svd(J[np.ix_(rows, cols)], compute_uv=False)
        if s[-1] <= 0 or s[0] / s[-1] > self.options.max_condition:
            return None
        return rows, cols

    def on_branch(self, sol: Solution) -> bool:
        """Whether a passive solve (Jacobian over the passive dofs kept) is on home's branch."""
        if self.idle_branch == 0.0:
            return True
        return (
            self._branch_det_sign(sol.jacobian[: self.queries.n_closure_rows]) == self.idle_branch
        )

    def solve_on_branch(self, q_act: np.ndarray, start: np.ndarray) -> Solution:
        """Closed configuration for ``q_act`` on the home branch, starting from ``start``.

        Raises:
            ConvergenceError: no solution on the home branch is reachable (the residual
                of the last attempt is attached).
        """
        # direct solves first, from the start then from home (so a guess never makes a
        # pose fail that the solve from home closes), then the continuations
        starts = [start] if start is self.q_home else [start, self.q_home]
        far: Solution | None = None  # on the branch, but far from its prediction
        for q0 in starts:
            try:
                sol, ok = self._step(q0, q_act, self.options)
                if ok:
                    return sol
                if far is None and self.on_branch(sol):
                    far = sol
            except ConvergenceError:
                pass
        last: ConvergenceError | None = None
        for q0 in starts:
            try:
                return self._continue(q0, q_act)
            except ConvergenceError as exc:
                last = exc
        if far is not None:  # no path gets there (e.g. next to a singularity): the sign
            return far  # is all there is to go by
        assert last is not None
        raise last

    def _continue(self, q: np.ndarray, q_act: np.ndarray) -> Solution:
        """Predictor-corrector continuation along the straight actuator path."""
        a0 = self.queries.actuators_of(q)
        t, h = 0.0, 0.25
        sol = None
        residual = np.inf
        corrector = corrector_options(self.options)
        while t < 1.0:
            h = min(h, 1.0 - t)
            a = a0 + (t + h) * (q_act - a0)
            ok = False
            try:
                cand, ok = self._step(q, a, corrector)
            except ConvergenceError as exc:
                residual = exc.residual
            if ok:
                q, sol, t = cand.q, cand, t + h
                h *= 2.0
            else:
                h /= 2.0
                if h < MIN_STEP:
                    raise ConvergenceError(
                        f"no solution on the home assembly branch along the path from "
                        f"q_act = {np.round(a0, 6).tolist()} (stopped at {t:.0%} of the path)",
                        residual=float(residual),
                    )
        assert sol is not None
        return sol

    def _step(self, q: np.ndarray, a: np.ndarray, options: SolverOptions) -> tuple[Solution, bool]:
        """One predictor-corrector step from the closed ``q`` to actuator values ``a``.

        The passive joints move as the first-order predictor says, then Newton corrects.
        The step is kept (True) when the solution is on home's branch and near the
        prediction: its correction is at most a quarter of the predicted passive motion
        (a solve that lands on another assembly mode — e.g. two legs of a Delta flipped,
        which keeps the sign of the branch determinant — moves far from it). A direct
        solve is this step over the whole path: never a bare Newton from a far start.

        Raises:
            ConvergenceError: the corrector does not converge.
        """
        pred = self._predict(q, a - self.queries.actuators_of(q))
        cand = self.newton(self.queries.with_actuators(pred, a), self._free_v, options=options)
        correction = pin.difference(self.model, pred, cand.q)[self._free_v]
        moved = pin.difference(self.model, q, pred)[self._free_v]
        near = np.linalg.norm(correction) <= 0.25 * np.linalg.norm(moved) + 1e-7
        return cand, bool(near and self.on_branch(cand))

    def _predict(self, q: np.ndarray, da: np.ndarray) -> np.ndarray:
        """First-order passive motion for an actuator step ``da`` (configuration).

        It also closes the residual at q to first order (a warm start from a neighbouring
        geometry: its step is the Newton step, not a far jump).
        """
        data = self.queries.compute(q)
        J, r = self.queries.jacobian_of(data), self.queries.residual_of(data)
        dv = np.zeros(self.model.nv)
        dv[self.queries.act_v_arr] = da
        rhs = -(J[:, self.queries.act_v_arr] @ da) - r  # closing an unclosed start too
        dv[self._free_v] = np.linalg.lstsq(J[:, self._free_v], rhs, rcond=None)[0]
        q_act_part = self.queries.with_actuators(q, self.queries.actuators_of(q) + da)
        dv_free = np.zeros(self.model.nv)
        dv_free[self._free_v] = dv[self._free_v]
        return pin.integrate(self.model, q_act_part, dv_free)

    def check_singular(self, sol: Solution, where: str, pose_index: int | None) -> None:
        """Raise when the passive closure Jacobian of a solution is ill-conditioned.

        Raises:
            SingularConfigurationError: its condition number (over the passive rank at
                home) exceeds ``options.max_condition``.
        """
        s = sol.singular_values
        r = self.passive_rank
        cond = s[0] / s[r - 1] if r and s[r - 1] > 0 else np.inf
        if r and cond > self.options.max_condition:
            raise SingularConfigurationError(
                f"singular configuration at {where}: closure Jacobian condition number "
                f"{cond:.3g} (limit {self.options.max_condition:.0e})",
                pose_index=pose_index,
                condition=float(cond),
            )

    def configuration(
        self, q_act: np.ndarray, q_guess: np.ndarray | None = None, pose_index: int | None = None
    ) -> np.ndarray:
        """Full configuration (nq,) with loops closed for actuator values ``q_act``.

        The solution stays on the assembly mode of :attr:`q_home`: a solve from
        ``q_guess`` (default home) that fails or lands on another branch is redone from
        home, then by continuation from the guess, then from home.

        Raises:
            ConvergenceError: no solution on the home branch (the message names the pose).
            SingularConfigurationError: the passive joints are not locally unique.
        """
        q_act = self.queries.check_q_act(q_act)
        guess = self.q_home if q_guess is None else self.queries.check_q(q_guess)
        if not self.closures:
            return self.queries.with_actuators(guess, q_act)
        where = f"pose {pose_index}" if pose_index is not None else "pose"
        try:
            sol = self.solve_on_branch(q_act, guess)
        except ConvergenceError as exc:
            raise ConvergenceError(
                f"forward kinematics failed at {where} (q_act = {np.round(q_act, 6).tolist()}): "
                f"the loops do not close on the assembly branch of home (residual "
                f"{say_length(exc.residual)}); {exc}",
                pose_index=pose_index,
                residual=exc.residual,
            ) from exc
        self.check_singular(sol, where, pose_index)
        return sol.q
