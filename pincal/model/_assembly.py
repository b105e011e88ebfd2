"""Assembly of a closed-loop mechanism: home configuration, mobility, singularity checks.

:class:`Assembly` is the part of :class:`~pincal.model.Mechanism` that closes the loops
(damped Newton from :mod:`pincal.model._newton`) and diagnoses what goes wrong.
"""

from __future__ import annotations

import itertools

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
from pincal.model._newton import Solution, SolverOptions, damped_newton

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
    def _newton(
        self,
        q0: np.ndarray,
        free: np.ndarray,
        extra=None,
        options: SolverOptions | None = None,
    ) -> Solution:
        """Damped Newton on the closure (+ optional extra) residual over tangent dofs ``free``.

        ``extra`` is a callable of the computed data returning ``(r (k,), J (k, nv))``;
        ``options`` replaces :attr:`options` for this solve.
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

        return damped_newton(self.model, q0, free, evaluate, jacobian, options or self.options)

    def _assemble(self, guess: np.ndarray, keep_actuators: bool = False) -> np.ndarray:
        """Close the loops from ``guess``.

        With ``keep_actuators`` only passive joints move (the actuator values of a
        user-given home are kept), else every joint may move.
        """
        if not self.closures:
            return guess
        if keep_actuators:
            try:
                return self._newton(guess, self._free_v).q
            except ConvergenceError:
                self._assembly_notes.append(
                    "the sidecar home actuator values do not close the loops: home was "
                    "assembled moving the actuated joints too"
                )
        all_v = np.arange(self.model.nv)
        try:
            sol = self._newton(guess, all_v)
        except ConvergenceError as exc:
            raise ClosureError(self._open_closure_diagnosis(guess, exc.residual)) from exc
        return sol.q

    def _open_closure_diagnosis(self, guess: np.ndarray, residual: float) -> str:
        """Why the loops stay open: frame names, the home guess, or the geometry."""
        r = self.closure_residual(guess)
        k = self._worst_closure_index(r)
        c = self.closures[k]
        k0 = sum(cc.size for cc in self.closures[:k])
        rows = self.closure_jacobian(guess)[k0 : k0 + c.size]
        head = (
            f"mechanism {self.name!r} cannot be assembled: closure {c.frame_a} ↔ {c.frame_b} "
            f"stays open (residual {residual * 1e3:.3f} mm/mrad after Newton; "
            f"{np.max(np.abs(r)) * 1e3:.3f} at the home guess). "
        )
        if self._same_body(c.frame_a, c.frame_b) or np.max(np.abs(rows), initial=0.0) < 1e-12:
            return head + (
                "No joint moves these two frames relative to each other: the frame names are "
                "probably wrong (sidecar 'closed_loop')."
            )
        rng = np.random.default_rng(0)
        for _ in range(8):
            start = pin.integrate(self.model, guess, 0.5 * rng.standard_normal(self.model.nv))
            try:
                self._newton(start, np.arange(self.model.nv))
            except ConvergenceError:
                continue
            return head + (
                "The loops do close from other starting configurations: the 'home' guess in "
                "the sidecar is at fault (give values nearer an assembled configuration)."
            )
        return head + (
            "The loops do not close from 8 other starts either: the geometry (link lengths, "
            "anchor positions) probably cannot close this loop, or the frame names are wrong."
        )

    def _same_body(self, frame_a: str, frame_b: str) -> bool:
        """Whether no joint of the Pinocchio model lies between the two frames."""
        fa, fb = (
            self.model.frames[self.frame_id(frame_a)],
            self.model.frames[self.frame_id(frame_b)],
        )
        return fa.parentJoint == fb.parentJoint

    def _worst_closure_index(self, r: np.ndarray) -> int:
        sizes = np.cumsum([0] + [c.size for c in self.closures])
        return int(np.argmax([np.max(np.abs(r[a:b])) for a, b in itertools.pairwise(sizes)]))

    def _passive_rank(self, q: np.ndarray) -> int:
        Jf = self.closure_jacobian(q)[:, self._free_v]
        if Jf.size == 0:
            return 0
        s = np.linalg.svd(Jf, compute_uv=False)
        return int(np.sum(s > self.options.rcond * s[0])) if s[0] > 0 else 0

    def _check_not_singular_home(self, rank_u: int) -> None:
        """Report a rank drop at home that disappears nearby as a singular home.

        Such a drop is not a mobility problem: say so (instead of "actuate more joints").
        """
        rng = np.random.default_rng(0)
        nearby = max(
            self._passive_rank(
                pin.integrate(self.model, self.q_home, 1e-3 * rng.standard_normal(self.model.nv))
            )
            for _ in range(3)
        )
        if nearby > rank_u:
            raise SingularConfigurationError(
                f"mechanism {self.name!r}: the home configuration is singular (passive closure "
                f"Jacobian rank {rank_u} at home, {nearby} nearby): the actuators do not hold "
                f"the passive joints there. Move 'home' in the sidecar (or q_guess) away from "
                f"the singularity, e.g. rotate or shift the platform a little",
                condition=float("inf"),
            )

    def _tangent_joint(self, v: int) -> str:
        m = self.model
        for j in range(1, m.njoints):
            if m.idx_vs[j] <= v < m.idx_vs[j] + m.nvs[j]:
                return m.names[j]
        return "?"

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
                if self.closures:
                    self._check_not_singular_home(rank_u)
                motion = np.abs(nullspace[:, moved > 1e-9]).max(axis=1)
                free = [
                    self._tangent_joint(int(self._free_v[k]))
                    for k in np.nonzero(motion > 0.1 * motion.max())[0]
                ]
                err = MobilityError(
                    f"mechanism {self.name!r}: {int(np.sum(moved > 1e-9))} passive degree(s) "
                    f"of freedom are not fixed by the {n_act} actuated joints "
                    f"{list(self.actuated)} and move the measured frame; free passive joints: "
                    f"{list(dict.fromkeys(free))}. Actuate one of them (sidecar 'name_mot') or "
                    f"add closures"
                )
                err.free_joints = tuple(dict.fromkeys(free))  # type: ignore[attr-defined]
                raise err
        if mobility != n_act or rank != rank_u:
            if self.closures:
                self._check_not_singular_home(rank_u)
            raise MobilityError(
                f"mechanism {self.name!r} has mobility {mobility} (nv {self.model.nv} − closure "
                f"rank {rank} − idle {idle}) but {n_act} actuated joints are declared "
                f"{list(self.actuated)}"
            )
        self._rank_u = rank_u
        self.mobility = mobility
        self.closure_rank = rank
        self.idle_joints = tuple(
            dict.fromkeys(
                self._tangent_joint(int(self._free_v[k]))
                for k in np.nonzero(np.abs(nullspace).max(axis=1) > 1e-6)[0]
            )
            if idle
            else ()
        )

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
