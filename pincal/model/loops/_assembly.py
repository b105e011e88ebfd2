"""Assembly of a closed-loop mechanism: the loop-closing Newton, home, mobility.

:func:`closure_newton` closes the loops of a
:class:`~pincal.model.loops._kinematics.KinematicQueries` (damped Newton from
:mod:`pincal.model.loops._newton`); :class:`Assembly` assembles the home configuration,
diagnoses why loops stay open and measures the mobility there (:class:`Mobility`).
"""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pincal.errors import (
    ClosureError,
    ConvergenceError,
    MobilityError,
    ModelFileError,
    SingularConfigurationError,
)
from pincal.model.loops._jacobian_shape import six_by_nv
from pincal.model.loops._kind_hint import open_loop_hint, spherical_hint
from pincal.model.loops._kinematics import KinematicQueries
from pincal.model.loops._newton import Solution, SolverOptions, damped_newton

__all__ = ["Assembly", "Mobility", "closure_newton", "model_size", "say_length"]

#: extra residual rows of a Newton solve: ``extra(data) -> (r (k,), J (k, nv))``
Extra = Callable[[pin.Data], tuple[np.ndarray, np.ndarray]]


def say_length(value: float) -> str:
    """A length [m] (or angle [rad]) in readable units: nm, µm, mm or m, 3 digits."""
    a = abs(value)
    if not np.isfinite(a):
        return f"{value} m"
    for unit, scale, below in (("nm", 1e9, 1e-6), ("µm", 1e6, 1e-3), ("mm", 1e3, 1.0)):
        if a < below:
            return f"{value * scale:.3g} {unit}"
    return f"{value:.3g} m"


def model_size(model: pin.Model) -> float:
    """The size of a model [m]: its longest joint or frame offset (at least 1 mm)."""
    offsets: list[float] = [float(np.linalg.norm(M.translation)) for M in model.jointPlacements]
    offsets += [float(np.linalg.norm(f.placement.translation)) for f in model.frames]
    return max([1e-3, *offsets])


def closure_newton(
    queries: KinematicQueries,
    q0: np.ndarray,
    free: np.ndarray,
    options: SolverOptions,
    extra: Extra | None = None,
) -> Solution:
    """Damped Newton on the closure (+ optional extra) residual over tangent dofs ``free``.

    ``extra`` is a callable of the computed data returning ``(r (k,), J (k, nv))``;
    with extra rows (inverse kinematics) the solve must close exactly: a target the
    mechanism cannot reach is no redundant closure (``redundant_tol`` 0).
    """
    if extra is not None and options.redundant_tol:
        options = dataclasses.replace(options, redundant_tol=0.0)
    data = queries.data()
    extra_jacobian = [np.zeros((0, queries.model.nv))]

    def evaluate(qq: np.ndarray) -> np.ndarray:
        queries.compute(qq)
        r = queries.residual_of(data)
        if extra is not None:
            r_extra, extra_jacobian[0] = extra(data)
            r = np.concatenate([r, r_extra])
        return r

    def jacobian() -> np.ndarray:
        J = queries.jacobian_of(data)
        return J if extra is None else np.vstack([J, extra_jacobian[0]])

    return damped_newton(queries.model, q0, free, evaluate, jacobian, options)


@dataclass(frozen=True)
class Mobility:
    """Mobility of a mechanism at home.

    Attributes:
        mobility: degrees of freedom (nv − closure rank − idle passive motions).
        closure_rank: rank of the closure Jacobian.
        passive_rank: rank of the passive closure Jacobian (over the passive dofs).
        idle_joints: passive joints the actuators do not hold and that do not move the
            measured frame.
    """

    mobility: int
    closure_rank: int
    passive_rank: int
    idle_joints: tuple[str, ...]


class Assembly:
    """Loop closing at home and its diagnoses.

    Args:
        queries: the kinematic queries of the mechanism.
        options: the Newton settings.
    """

    def __init__(self, queries: KinematicQueries, options: SolverOptions):
        self.queries, self.options = queries, options
        self.model, self.name, self.closures = queries.model, queries.name, queries.closures
        #: remarks gathered while assembling (for ``pincal info``)
        self.notes: list[str] = []

    def _newton(self, q0: np.ndarray, free: np.ndarray) -> Solution:
        return closure_newton(self.queries, q0, free, self.options)

    def home_guess(self, home: Mapping[str, object]) -> np.ndarray:
        """The configuration (nq,) of the sidecar ``home`` values (neutral elsewhere)."""
        q = pin.neutral(self.model)
        for name, value in home.items():
            j = self.queries.joint_id(name)
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

    def assemble(
        self, guess: np.ndarray, keep_actuators: bool = False, beside: bool = False
    ) -> np.ndarray:
        """Close the loops from ``guess``.

        With ``keep_actuators`` only passive joints move (the actuator values of a
        user-given home are kept), else every joint may move. With ``beside`` (``guess``
        is the home of a slightly different geometry, e.g. the nominal machine's) a
        Newton that stalls at ``guess`` is restarted beside it; a user's home guess where
        Newton stalls is refused instead (near a singularity it names no assembly mode).
        """
        if not self.closures:
            return guess
        if keep_actuators:
            try:
                return self._newton(guess, self.queries.free_v).q
            except ConvergenceError:
                self.notes.append(
                    "the sidecar home actuator values do not close the loops: home was "
                    "assembled moving the actuated joints too"
                )
        all_v = np.arange(self.model.nv)
        try:
            sol = self._newton(guess, all_v)
        except ConvergenceError as exc:
            near = self._nearby_assembly(guess, all_v) if beside else None
            if near is None:
                raise ClosureError(self._open_closure_diagnosis(guess, exc.residual)) from exc
            sol = near
            self.notes.append(
                "Newton stalls at the nominal home (a singular configuration, e.g. a dead "
                "point): home was assembled from a start 0.01–0.1 rad (or m) beside it"
            )
        if sol.remainder > 0.0:
            self.notes.append(self._least_squares_note(sol))
        return sol.q

    def _nearby_assembly(self, guess: np.ndarray, free: np.ndarray) -> Solution | None:
        """The closed configuration nearest ``guess`` from starts beside it, or None.

        Newton starts 0.01, then 0.1 (rad or m, each tangent dof) off ``guess``.

        At a singular guess (a four-bar's dead point) the Newton step has no component
        along the motion that would close a slightly perturbed loop, and Newton stalls
        where a start a little off the singularity converges.
        """
        rng = np.random.default_rng(0)
        found: list[tuple[float, Solution]] = []
        for size in (1e-2, 1e-1):
            for _ in range(4):
                start = pin.integrate(self.model, guess, size * rng.standard_normal(self.model.nv))
                try:
                    sol = self._newton(start, free)
                except ConvergenceError:
                    continue
                found.append((float(np.linalg.norm(pin.difference(self.model, guess, sol.q))), sol))
            if found:
                return min(found, key=lambda pair: pair[0])[1]
        return None

    def _redundant_loops(self, q: np.ndarray, tol: float) -> list[str]:
        """The closures (``a ↔ b``) with a residual row above ``tol`` at q."""
        r = np.abs(self.queries.closure_residual(q))
        sizes = np.cumsum([0] + [c.size for c in self.closures])
        return [
            f"{c.frame_a} ↔ {c.frame_b}"
            for c, (a, b) in zip(self.closures, itertools.pairwise(sizes), strict=True)
            if np.max(r[a:b], initial=0.0) > tol
        ]

    def _least_squares_note(self, sol: Solution) -> str:
        loops = self._redundant_loops(sol.q, self.options.tol)
        return (
            f"loop{'s' if len(loops) > 1 else ''} {', '.join(loops)} "
            f"{'are' if len(loops) > 1 else 'is'} over-constrained: closed to "
            f"{sol.residual:.2g} m in the least-squares sense (redundant closure rows the "
            f"geometry cannot close exactly, e.g. numbers rounded by a CAD export; accepted "
            f"up to {self.options.redundant_tol:.2g} m, 1e-6 of the model size)"
        )

    def _open_closure_diagnosis(self, guess: np.ndarray, residual: float) -> str:
        """Why the loops stay open: frame names, the home guess, or the geometry.

        A geometric refusal ends with the joint-kind hint
        (:func:`~pincal.model.loops._kind_hint.open_loop_hint`) when ball ends would close it.
        """
        return self._open_closure_cause(guess, residual) + open_loop_hint(
            self.queries, guess, self.options.rcond
        )

    def _open_closure_cause(self, guess: np.ndarray, residual: float) -> str:
        r = self.queries.closure_residual(guess)
        k = self._worst_closure_index(r)
        c = self.closures[k]
        k0 = sum(cc.size for cc in self.closures[:k])
        rows = self.queries.closure_jacobian(guess)[k0 : k0 + c.size]
        head = (
            f"mechanism {self.name!r} cannot be assembled: closure {c.frame_a} ↔ {c.frame_b} "
            f"stays open (residual {say_length(residual)} (or rad) after Newton; "
            f"{say_length(float(np.max(np.abs(r))))} at the home guess). "
        )
        rank = int(
            np.linalg.matrix_rank(rows, tol=self.options.rcond * max(np.abs(rows).max(), 1e-300))
        )
        if 0 < rank < c.size and residual <= 1e3 * (self.options.redundant_tol or 0.0):
            return head + (
                f"The closure is over-constrained (its {c.size} rows have rank {rank}): it "
                f"closes only in the least-squares sense, and the redundant rows miss by "
                f"more than the {say_length(self.options.redundant_tol or 0.0)} accepted "
                f"(1e-6 of the model size). Make the redundant geometry consistent (e.g. "
                f"parallel axes, anchors in one plane, numbers not rounded), or declare the "
                f"closure with fewer components ('3d', or pincal's 'planar'/'revolute' kinds)."
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
            self.model.frames[self.queries.frame_id(frame_a)],
            self.model.frames[self.queries.frame_id(frame_b)],
        )
        return fa.parentJoint == fb.parentJoint

    def _worst_closure_index(self, r: np.ndarray) -> int:
        sizes = np.cumsum([0] + [c.size for c in self.closures])
        return int(np.argmax([np.max(np.abs(r[a:b])) for a, b in itertools.pairwise(sizes)]))

    def _passive_rank(self, q: np.ndarray) -> int:
        Jf = self.queries.closure_jacobian(q)[:, self.queries.free_v]
        if Jf.size == 0:
            return 0
        s = np.linalg.svd(Jf, compute_uv=False)
        return int(np.sum(s > self.options.rcond * s[0])) if s[0] > 0 else 0

    def _check_not_singular_home(self, q_home: np.ndarray, rank_u: int) -> None:
        """Report a rank drop at home that disappears nearby as a singular home.

        Such a drop is not a mobility problem: say so (instead of "actuate more joints").
        """
        rng = np.random.default_rng(0)
        nearby = max(
            self._passive_rank(
                pin.integrate(self.model, q_home, 1e-3 * rng.standard_normal(self.model.nv))
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

    def mobility(self, q_home: np.ndarray) -> Mobility:
        """The mobility at the assembled home ``q_home`` (nq,).

        Raises:
            MobilityError: the actuated joints do not fix the measured frame, or their
                number is not the mobility.
            SingularConfigurationError: home is singular (the rank drops only there).
        """
        free_v = self.queries.free_v
        data = self.queries.compute(q_home)
        Jc = self.queries.jacobian_of(data)
        n_act = len(self.queries.actuated)
        if Jc.shape[0] == 0:
            rank, rank_u, nullspace = 0, 0, np.eye(free_v.size)
        else:
            s = np.linalg.svd(Jc, compute_uv=False)
            rank = int(np.sum(s > self.options.rcond * s[0])) if s[0] > 0 else 0
            _, su, Vt = np.linalg.svd(Jc[:, free_v])
            rank_u = int(np.sum(su > self.options.rcond * su[0])) if su[0] > 0 else 0
            nullspace = Vt[rank_u:].T
        idle = free_v.size - rank_u
        mobility = self.model.nv - rank - idle
        if idle:  # passive motions the actuators do not fix must not move the measured frame
            fid = self.queries.frame_id(self.queries.measured_frame)
            Jm = six_by_nv(pin.getFrameJacobian(self.model, data, fid, pin.LOCAL))[:, free_v]
            moved = np.linalg.norm(Jm @ nullspace, axis=0)
            if np.any(moved > 1e-9):
                if self.closures:
                    self._check_not_singular_home(q_home, rank_u)
                motion = np.abs(nullspace[:, moved > 1e-9]).max(axis=1)
                free = [
                    self._tangent_joint(int(free_v[k]))
                    for k in np.nonzero(motion > 0.1 * motion.max())[0]
                ]
                err = MobilityError(
                    f"mechanism {self.name!r}: {int(np.sum(moved > 1e-9))} passive degree(s) "
                    f"of freedom are not fixed by the {n_act} actuated joints "
                    f"{list(self.queries.actuated)} and move the measured frame; free passive "
                    f"joints: "
                    f"{list(dict.fromkeys(free))}. Actuate one of them (sidecar 'name_mot') or "
                    f"add closures." + spherical_hint(self.queries, q_home, self.options.rcond)
                )
                err.free_joints = tuple(dict.fromkeys(free))  # type: ignore[attr-defined]
                raise err
        if mobility != n_act or rank != rank_u:
            if self.closures:
                self._check_not_singular_home(q_home, rank_u)
            raise MobilityError(
                f"mechanism {self.name!r} has mobility {mobility} (nv {self.model.nv} − closure "
                f"rank {rank} − idle {idle}) but {n_act} actuated joints are declared "
                f"{list(self.queries.actuated)}."
                + spherical_hint(self.queries, q_home, self.options.rcond)
            )
        idle_joints = (
            tuple(
                dict.fromkeys(
                    self._tangent_joint(int(free_v[k]))
                    for k in np.nonzero(np.abs(nullspace).max(axis=1) > 1e-6)[0]
                )
            )
            if idle
            else ()
        )
        return Mobility(mobility, rank, rank_u, idle_joints)
