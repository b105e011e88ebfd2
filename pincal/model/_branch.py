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
* a direct solve from the start configuration that fails this test is followed by a
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

from pincal.errors import ConvergenceError
from pincal.model._assembly import Assembly
from pincal.model._newton import Solution, SolverOptions

__all__ = ["BranchTracking"]

_MIN_STEP = 1.0 / 4096  # smallest continuation step, as a fraction of the path
#: corrector budget of one continuation step: converging correctors take <= 9 iterations
#: and (almost) never backtrack on the bundled machines
_CORRECTOR_ITERATIONS = 12
_CORRECTOR_BACKTRACKS = 4


def corrector_options(options: SolverOptions) -> SolverOptions:
    """The short-budget Newton settings of a continuation corrector (same tolerances)."""
    return dataclasses.replace(
        options,
        max_iterations=min(options.max_iterations, _CORRECTOR_ITERATIONS),
        max_backtracks=min(options.max_backtracks, _CORRECTOR_BACKTRACKS),
    )


class BranchTracking(Assembly):
    """Branch-preserving loop closing (mixed into Mechanism)."""

    def _branch_det_sign(self, Jf: np.ndarray) -> float:
        """Sign of det of the branch block of a passive closure Jacobian (rows, n_free)."""
        if self._branch_block is None:
            return 0.0
        rows, cols = self._branch_block
        return float(np.sign(np.linalg.det(Jf[np.ix_(rows, cols)])))

    def _branch_sign(self, q: np.ndarray) -> float:
        """Sign of det of the (reduced) passive closure Jacobian at q, 0 if undefined."""
        if self._branch_block is None:
            return 0.0
        return self._branch_det_sign(self.closure_jacobian(q)[:, self._free_v])

    def _init_branch(self) -> None:
        n, rows, r = self._free_v.size, self.n_closure_rows, self._rank_u
        self._square_passive = bool(self.closures and rows == n and r == n)
        self._branch_block: tuple[np.ndarray, np.ndarray] | None = None
        if self._square_passive:
            self._branch_block = (np.arange(n), np.arange(n))
        elif self.closures and r > 0:
            self._branch_block = self._reduced_block()
        sign = self._branch_sign(self.q_home)
        self.home_branch = sign if self._square_passive else 0.0
        #: the branch sign of the square block of rank rows and non-idle columns
        #: (= home_branch when the passive closure Jacobian is square; 0: no branch)
        self.idle_branch = sign

    def _reduced_block(self) -> tuple[np.ndarray, np.ndarray] | None:
        """Independent rows and non-idle columns of the passive closure Jacobian at home.

        None when that square block is not well-conditioned at home (then no branch is
        checked, as before).
        """
        import scipy.linalg  # here: importing pincal must not load scipy

        J = self.closure_jacobian(self.q_home)[:, self._free_v]
        r = self._rank_u
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

    def _on_branch(self, sol: Solution) -> bool:
        """Whether a passive solve (Jacobian over the passive dofs kept) is on home's branch."""
        if self.idle_branch == 0.0:
            return True
        return self._branch_det_sign(sol.jacobian[: self.n_closure_rows]) == self.idle_branch

    def _solve_on_branch(self, q_act: np.ndarray, start: np.ndarray) -> Solution:
        """Closed configuration for ``q_act`` on the home branch, starting from ``start``.

        Raises:
            ConvergenceError: no solution on the home branch is reachable (the residual
                of the last attempt is attached).
        """
        # direct solves first, from the start then from home (so a guess never makes a
        # pose fail that the solve from home closes), then the continuations
        starts = [start] if start is self.q_home else [start, self.q_home]
        for q0 in starts:
            try:
                sol = self._newton(self.with_actuators(q0, q_act), self._free_v)
                if self._on_branch(sol):
                    return sol
            except ConvergenceError:
                pass
        last: ConvergenceError | None = None
        for q0 in starts:
            try:
                return self._continue(q0, q_act)
            except ConvergenceError as exc:
                last = exc
        assert last is not None
        raise last

    def _continue(self, q: np.ndarray, q_act: np.ndarray) -> Solution:
        """Predictor-corrector continuation along the straight actuator path."""
        a0 = self.actuators_of(q)
        t, h = 0.0, 0.25
        sol = None
        residual = np.inf
        corrector = corrector_options(self.options)
        while t < 1.0:
            h = min(h, 1.0 - t)
            a = a0 + (t + h) * (q_act - a0)
            ok = False
            try:
                pred = self._predict(q, a - self.actuators_of(q))
                cand = self._newton(self.with_actuators(pred, a), self._free_v, options=corrector)
                correction = pin.difference(self.model, pred, cand.q)[self._free_v]
                moved = pin.difference(self.model, q, pred)[self._free_v]
                ok = self._on_branch(cand) and (
                    np.linalg.norm(correction) <= 0.25 * np.linalg.norm(moved) + 1e-7
                )
            except ConvergenceError as exc:
                residual = exc.residual
            if ok:
                q, sol, t = cand.q, cand, t + h
                h *= 2.0
            else:
                h /= 2.0
                if h < _MIN_STEP:
                    raise ConvergenceError(
                        f"no solution on the home assembly branch along the path from "
                        f"q_act = {np.round(a0, 6).tolist()} (stopped at {t:.0%} of the path)",
                        residual=float(residual),
                    )
        assert sol is not None
        return sol

    def _predict(self, q: np.ndarray, da: np.ndarray) -> np.ndarray:
        """First-order passive motion for an actuator step ``da`` (configuration)."""
        J = self.closure_jacobian(q)
        dv = np.zeros(self.model.nv)
        dv[self._act_v_arr] = da
        rhs = -(J[:, self._act_v_arr] @ da)
        dv[self._free_v] = np.linalg.lstsq(J[:, self._free_v], rhs, rcond=None)[0]
        q_act_part = self.with_actuators(q, self.actuators_of(q) + da)
        dv_free = np.zeros(self.model.nv)
        dv_free[self._free_v] = dv[self._free_v]
        return pin.integrate(self.model, q_act_part, dv_free)
