"""Assembly of a closed-loop mechanism: home configuration, mobility, singularity checks.

:class:`Assembly` is the part of :class:`~pincal.model.Mechanism` that closes the loops
(damped Newton from :mod:`pincal.model._newton`) and diagnoses what goes wrong.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from pincal.errors import (
    ClosureError,
    ConvergenceError,
    MobilityError,
    ModelFileError,
    SingularConfigurationError,
)
from pincal.model._kinematics import KinematicQueries
from pincal.model._newton import Solution, damped_newton

__all__ = ["Assembly"]


class Assembly(KinematicQueries):
    """Loop closing and its diagnoses (mixed into Mechanism)."""

    def _home_guess(self) -> np.ndarray:
        q = pin.neutral(self.model)
        for name, value in self.sidecar.home.items():
            j = self.joint_id(name)
            qi, nq = self.model.idx_qs[j], self.model.nqs[j]
            vals = np.atleast_1d(np.asarray(value, dtype=float))
            if nq == 7 and vals.size == 6:  # floating: x y z roll pitch yaw
                quat = pin.Quaternion(pin.rpy.rpyToMatrix(*vals[3:]))
                vals = np.concatenate([vals[:3], quat.coeffs()])
            elif nq == 2 and vals.size == 1:  # unbounded revolute
                vals = np.array([np.cos(vals[0]), np.sin(vals[0])])
            if vals.size != nq:
                raise ModelFileError(f"sidecar home[{name!r}] needs {nq} values, got {vals.size}")
            q[qi : qi + nq] = vals
        return q

    # ---------------------------------------------------------------- kinematics core
    def _newton(self, q0: np.ndarray, free: np.ndarray, extra=None) -> Solution:
        """Damped Newton on the closure (+ optional extra) residual over tangent dofs ``free``.

        ``extra`` is a callable of the computed data returning ``(r (k,), J (k, nv))``.
        """
        data = self._data()
        extra_jacobian = [np.zeros((0, self.model.nv))]

        def evaluate(qq: np.ndarray) -> np.ndarray:
            self._compute(qq)
            r = self._closure_residual(data)
            if extra is not None:
                r_extra, extra_jacobian[0] = extra(data)
                r = np.concatenate([r, r_extra])
            return r

        def jacobian() -> np.ndarray:
            J = self._closure_jacobian(data)
            return J if extra is None else np.vstack([J, extra_jacobian[0]])

        return damped_newton(self.model, q0, free, evaluate, jacobian, self.options)

    def _assemble(self, guess: np.ndarray) -> np.ndarray:
        if not self.closures:
            return guess
        all_v = np.arange(self.model.nv)
        try:
            sol = self._newton(guess, all_v)
        except ConvergenceError as exc:
            r = self.closure_residual(guess)
            worst = self._worst_closure(r)
            raise ClosureError(
                f"mechanism {self.name!r} cannot be assembled: closure {worst} stays open "
                f"(residual {exc.residual * 1e3:.3f} mm/mrad after Newton; "
                f"{np.max(np.abs(r)) * 1e3:.3f} at the home guess). Check the closure "
                f"frame names and the 'home' guess in the sidecar."
            ) from exc
        return sol.q

    def _worst_closure(self, r: np.ndarray) -> str:
        best, k0, where = -1.0, 0, ""
        for c in self.closures:
            v = float(np.max(np.abs(r[k0 : k0 + c.size])))
            if v > best:
                best, where = v, f"{c.frame_a} ↔ {c.frame_b}"
            k0 += c.size
        return where

    def _check_mobility(self) -> None:
        data = self._compute(self.q_home)
        Jc = self._closure_jacobian(data)
        n_act = len(self.actuated)
        if Jc.shape[0] == 0:
            rank, rank_u, nullspace = 0, 0, np.eye(self._free_v.size)
        else:
            s = np.linalg.svd(Jc, compute_uv=False)
            rank = int(np.sum(s > self.options.rcond * s[0])) if s[0] > 0 else 0
            _, su, Vt = np.linalg.svd(Jc[:, self._free_v])
            rank_u = int(np.sum(su > self.options.rcond * su[0])) if su[0] > 0 else 0
            nullspace = Vt[rank_u:].T
        idle = self._free_v.size - rank_u
        mobility = self.model.nv - rank - idle
        if idle:  # passive motions the actuators do not fix must not move the measured frame
            fid = self.frame_id(self.measured_frame)
            Jm = pin.getFrameJacobian(self.model, data, fid, pin.LOCAL)[:, self._free_v]
            moved = np.linalg.norm(Jm @ nullspace, axis=0)
            if np.any(moved > 1e-9):
                raise MobilityError(
                    f"mechanism {self.name!r}: {idle} passive degree(s) of freedom are not fixed "
                    f"by the {n_act} actuated joints {list(self.actuated)} and move the measured "
                    f"frame; actuate more joints or add closures"
                )
        if mobility != n_act or rank != rank_u:
            raise MobilityError(
                f"mechanism {self.name!r} has mobility {mobility} (nv {self.model.nv} − closure "
                f"rank {rank} − idle {idle}) but {n_act} actuated joints are declared "
                f"{list(self.actuated)}"
            )
        self._rank_u = rank_u
        self.mobility = mobility

    # ------------------------------------------------------------------ public API
    def _check_singular(self, sol: Solution, where: str, pose_index: int | None) -> None:
        s = sol.singular_values
        r = self._rank_u
        cond = s[0] / s[r - 1] if r and s[r - 1] > 0 else np.inf
        if r and cond > self.options.max_condition:
            raise SingularConfigurationError(
                f"singular configuration at {where}: closure Jacobian condition number "
                f"{cond:.3g} (limit {self.options.max_condition:.0e})",
                pose_index=pose_index,
                condition=float(cond),
            )
