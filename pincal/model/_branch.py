"""Forward kinematics that stays on the assembly mode (branch) of the home configuration.

A closed loop usually closes in several ways for the same actuator values (knees up or
down). A Newton solve warm-started from an arbitrary configuration can land on any of
them. Here a solution is accepted only when it is on the branch of ``q_home``:

* where the passive closure Jacobian is square, the sign of its determinant must equal
  the sign at home (it changes exactly when a passive singularity is crossed);
* a direct solve from the start configuration that fails this test is replaced by a
  continuation: a straight path in actuator space from the start (then from home),
  in steps that halve until each step converges, keeps the sign and moves the passive
  joints as the first-order predictor says.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from pincal.errors import ConvergenceError
from pincal.model._assembly import Assembly
from pincal.model._newton import Solution

__all__ = ["BranchTracking"]

_MIN_STEP = 1.0 / 4096  # smallest continuation step, as a fraction of the path


class BranchTracking(Assembly):
    """Branch-preserving loop closing (mixed into Mechanism)."""

    def _branch_sign(self, q: np.ndarray) -> float:
        """Sign of det of the passive closure Jacobian at q, or 0 where undefined."""
        if not self._square_passive:
            return 0.0
        J = self.closure_jacobian(q)[:, self._free_v]
        return float(np.sign(np.linalg.det(J)))

    def _init_branch(self) -> None:
        n = self._free_v.size
        self._square_passive = bool(
            self.closures and self.n_closure_rows == n and self._rank_u == n
        )
        self.home_branch = self._branch_sign(self.q_home)

    def _on_branch(self, sol: Solution) -> bool:
        """Whether a passive solve (Jacobian over the passive dofs kept) is on home's branch."""
        if self.home_branch == 0.0:
            return True
        J = sol.jacobian[: self.n_closure_rows]
        return float(np.sign(np.linalg.det(J))) == self.home_branch

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
