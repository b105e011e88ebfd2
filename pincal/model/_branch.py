"""Forward kinematics that stays on the assembly mode (branch) of the home configuration.

A closed loop usually closes in several ways for the same actuator values (knees up or
down). A Newton solve warm-started from an arbitrary configuration can land on any of
them. Here a solution is accepted only when it is on the branch of ``q_home``:

* where the passive closure Jacobian is square, the sign of its determinant must equal
  the sign at home (it changes exactly when a passive singularity is crossed);
* where it has independent rows but more columns because some passive motion is idle
  (e.g. the spin of an RSSR coupler about its own axis: it moves nothing the closures
  or the measured frame see), the idle directions are left out: the columns carrying
  most of the idle motion at home are dropped (column-pivoted QR of the home
  nullspace) and the sign of the determinant of the remaining square block is checked
  instead (``idle_branch``; ``home_branch`` stays 0 for such mechanisms);
* a direct solve from the start configuration that fails this test is replaced by a
  continuation: a straight path in actuator space from the start (then from home),
  in steps that halve until each step converges, keeps the sign and moves the passive
  joints as the first-order predictor says.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import scipy.linalg

from pincal.errors import ConvergenceError
from pincal.model._assembly import Assembly
from pincal.model._newton import Solution

__all__ = ["BranchTracking"]

_MIN_STEP = 1.0 / 4096  # smallest continuation step, as a fraction of the path


class BranchTracking(Assembly):
    """Branch-preserving loop closing (mixed into Mechanism)."""

    def _branch_sign(self, q: np.ndarray) -> float:
        """Sign of det of the (idle-reduced) passive closure Jacobian at q, 0 if undefined."""
        if self._branch_cols is None:
            return 0.0
        J = self.closure_jacobian(q)[:, self._free_v[self._branch_cols]]
        return float(np.sign(np.linalg.det(J)))

    def _init_branch(self) -> None:
        n = self._free_v.size
        rows = self.n_closure_rows
        self._square_passive = bool(self.closures and rows == n and self._rank_u == n)
        self._branch_cols: np.ndarray | None = None
        if self._square_passive:
            self._branch_cols = np.arange(n)
        elif self.closures and 0 < rows == self._rank_u < n:
            self._branch_cols = self._non_idle_columns()
        sign = self._branch_sign(self.q_home)
        self.home_branch = sign if self._square_passive else 0.0
        #: the branch sign with the idle passive directions left out (= home_branch when
        #: there are none; 0 where no branch is defined)
        self.idle_branch = sign

    def _non_idle_columns(self) -> np.ndarray | None:
        """Local passive columns left when the idle directions at home are dropped.

        None when the remaining square block is not well-conditioned at home (then no
        branch is checked, as before).
        """
        J = self.closure_jacobian(self.q_home)[:, self._free_v]
        _, _, Vt = np.linalg.svd(J)
        null = Vt[self._rank_u :]  # (idle, n): the idle directions at home
        _, _, piv = scipy.linalg.qr(null, pivoting=True)
        keep = np.sort(piv[null.shape[0] :])
        s = np.linalg.svd(J[:, keep], compute_uv=False)
        if s[-1] <= 0 or s[0] / s[-1] > self.options.max_condition:
            return None
        return keep

    def _on_branch(self, sol: Solution) -> bool:
        """Whether a passive solve (Jacobian over the passive dofs kept) is on home's branch."""
        if self.idle_branch == 0.0 or self._branch_cols is None:
            return True
        J = sol.jacobian[: self.n_closure_rows][:, self._branch_cols]
        return float(np.sign(np.linalg.det(J))) == self.idle_branch

    def _solve_on_branch(self, q_act: np.ndarray, start: np.ndarray) -> Solution:
        """Closed configuration for ``q_act`` on the home branch, starting from ``start``.

        Raises:
            ConvergenceError: no solution on the home branch is reachable (the residual
                of the last attempt is attached).
        """
        try:
            sol = self._newton(self.with_actuators(start, q_act), self._free_v)
            if self._on_branch(sol):
                return sol
        except ConvergenceError:
            pass
        starts = [start] if start is self.q_home else [start, self.q_home]
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
        while t < 1.0:
            h = min(h, 1.0 - t)
            a = a0 + (t + h) * (q_act - a0)
            ok = False
            try:
                pred = self._predict(q, a - self.actuators_of(q))
                cand = self._newton(self.with_actuators(pred, a), self._free_v)
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
