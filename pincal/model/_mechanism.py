"""Mechanism: a URDF spanning tree, its loop closures, actuation and measured frame.

A :class:`Mechanism` is immutable: applying parameter values or calibrating returns a
new one. Configuration vectors ``q`` are Pinocchio configurations (size ``nq``;
quaternions are x, y, z, w); actuator vectors ``q_act`` hold one value per actuated
joint in the order of :attr:`Mechanism.actuated` [m or rad].
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
import yaml

from pincal.errors import (
    ClosureError,
    ConvergenceError,
    MobilityError,
    ModelFileError,
    SingularConfigurationError,
    UnknownNameError,
    UnreachablePoseError,
)
from pincal.model._closures import (
    COMPONENTS,
    Closure,
    measured_jacobian,
    parse_components,
)
from pincal.model._sidecar import WORKSPACE_POSE_KEYS, Sidecar, Workspace, validate_sidecar
from pincal.model._urdf import UrdfTree

__all__ = [
    "WORKSPACE_POSE_KEYS",
    "Kinematics",
    "Mechanism",
    "Sidecar",
    "SolverOptions",
    "Workspace",
    "bundled_models",
    "load_mechanism",
    "read_sidecar",
    "resolve_model_path",
    "validate_sidecar",
]

log = logging.getLogger(__name__)

MODELS_DIR = Path(__file__).resolve().parents[2] / "models"


@dataclass(frozen=True)
class SolverOptions:
    """Newton solver settings.

    Attributes:
        tol: convergence threshold on the largest residual component [m or rad].
        max_iterations: Newton iterations before giving up.
        max_step: largest tangent step norm per iteration [m, rad].
        rcond: relative singular-value cut-off of the rank-revealing solve.
        max_condition: condition number above which a solution is called singular.
    """

    tol: float = 1e-12
    max_iterations: int = 60
    max_step: float = 0.5
    rcond: float = 1e-10
    max_condition: float = 1e8


@dataclass(frozen=True)
class Kinematics:
    """Kinematics of one configuration: fresh arrays, nothing shared with the mechanism.

    Attributes:
        q: (nq,) the configuration.
        placements: world placement of each kept frame (by name).
        jacobians: (6, nv) LOCAL Jacobian of each kept frame (by name).
        joint_placements: world placement of every joint (index = Pinocchio joint id).
        closure_residual: (n_closure_rows,) [m, rad].
        closure_jacobian: (n_closure_rows, nv).
    """

    q: np.ndarray
    placements: Mapping[str, pin.SE3]
    jacobians: Mapping[str, np.ndarray]
    joint_placements: tuple[pin.SE3, ...]
    closure_residual: np.ndarray
    closure_jacobian: np.ndarray


@dataclass(frozen=True)
class _Solution:
    q: np.ndarray
    iterations: int
    residual: float
    singular_values: np.ndarray  # of the Jacobian over the free dofs at q


def _newton_step(J: np.ndarray, r: np.ndarray, rcond: float) -> np.ndarray:
    """Minimum-norm least-squares solution of ``J dx = −r`` (rank-revealing).

    A square, well-conditioned J is solved by LU; anything else (redundant closure rows,
    rank loss) by a truncated SVD with relative cut-off ``rcond``.
    """
    if J.shape[0] == J.shape[1] and J.size:
        try:
            step = -np.linalg.solve(J, r)
            if np.all(np.isfinite(step)) and np.linalg.norm(J @ step + r) <= 1e-8 * (
                np.linalg.norm(r) + 1e-300
            ):
                return step
        except np.linalg.LinAlgError:
            pass
    U, s, Vt = np.linalg.svd(J, full_matrices=False)
    if s.size == 0 or s[0] == 0.0:
        return np.zeros(J.shape[1])
    keep = s > rcond * s[0]
    coeff = (U.T @ r)[keep] / s[keep]
    return -(Vt[keep].T @ coeff)


class Mechanism:
    """A mechanism loaded from URDF (+ sidecar).

    Use :func:`load_mechanism` to create one. Attributes of interest:

    * ``model``: the Pinocchio model (do not modify);
    * ``actuated``: actuated joint names; ``closures``: the loop closures;
    * ``measured_frame`` and ``measured_components`` (names from x y z rx ry rz);
    * ``q_home``: assembled home configuration (nq,);
    * ``workspace``: :class:`Workspace`; ``presets``: raw parameter presets.
    """

    def __init__(
        self,
        urdf_xml: str,
        sidecar: Sidecar | Mapping[str, Any] | None = None,
        *,
        name: str | None = None,
        source: Path | None = None,
        measured_frame: str | None = None,
        q_guess: np.ndarray | None = None,
        options: SolverOptions | None = None,
    ):
        self.urdf_xml = urdf_xml
        self.tree = UrdfTree(urdf_xml)
        self.sidecar: Sidecar = Sidecar.from_dict(sidecar)
        self.name = name or self.tree.name
        self.source = source
        self.options = options or SolverOptions()
        try:
            self.model = pin.buildModelFromXML(urdf_xml)
        except (RuntimeError, ValueError) as exc:
            raise ModelFileError(f"Pinocchio cannot build the URDF model: {exc}") from exc
        self._scratch = threading.local()  # per-thread pin.Data, never read across calls
        self._frame_ids = {f.name: i for i, f in enumerate(self.model.frames)}
        self.closures = self._parse_closures()
        self.actuated = self._parse_actuated()
        self._setup_indices()
        self.measured_frame = self._resolve_measured_frame(measured_frame)
        #: the frames a sensitivity needs: the measured frame and every closure frame
        self.key_frames = tuple(
            dict.fromkeys(
                [self.measured_frame] + [f for c in self.closures for f in (c.frame_a, c.frame_b)]
            )
        )
        self.measured_components = tuple(
            COMPONENTS[i] for i in parse_components(self.sidecar.measured, "sidecar 'measured'")
        )
        self.presets: dict[str, Any] = dict(self.sidecar.presets)
        self.workspace = self._parse_workspace()
        guess = self._home_guess() if q_guess is None else np.asarray(q_guess, dtype=float)
        self.q_home = self._assemble(guess)
        self._check_mobility()

    # ------------------------------------------------------------------ set-up
    def frame_id(self, name: str) -> int:
        """Pinocchio frame index of a frame (URDF link or joint) by name."""
        if name not in self._frame_ids:
            raise UnknownNameError("frame", name, self.tree.links)
        return self._frame_ids[name]

    def joint_id(self, name: str) -> int:
        if not self.model.existJointName(name):
            raise UnknownNameError("joint", name, list(self.model.names)[1:])
        return self.model.getJointId(name)

    def _parse_closures(self) -> tuple[Closure, ...]:
        closures = []
        for k, ((a, b), kind) in enumerate(
            zip(self.sidecar.closed_loop, self.sidecar.type, strict=True)
        ):
            self.frame_id(a)
            self.frame_id(b)
            comps = parse_components(kind, f"sidecar type[{k}]")
            label = kind if isinstance(kind, str) else " ".join(kind)
            closures.append(Closure(a, b, comps, label))
        return tuple(closures)

    def _parse_actuated(self) -> tuple[str, ...]:
        movable = [
            self.model.names[j]
            for j in range(1, self.model.njoints)
            if self.model.joints[j].nv == 1
        ]
        names = self.sidecar.name_mot
        if names is None:
            if self.closures:
                raise ModelFileError(
                    "a closed-loop mechanism needs 'name_mot' (actuated joints) in its sidecar"
                )
            return tuple(movable)
        for n in names:
            if n not in movable:
                raise UnknownNameError("actuated joint", str(n), movable)
        if len(set(names)) != len(names):
            raise ModelFileError(f"sidecar 'name_mot' lists a joint twice: {names}")
        return tuple(str(n) for n in names)

    def _setup_indices(self) -> None:
        model = self.model
        self._act_q, self._act_v, self._act_nq = [], [], []
        for n in self.actuated:
            j = model.getJointId(n)
            self._act_q.append(model.idx_qs[j])
            self._act_v.append(model.idx_vs[j])
            self._act_nq.append(model.nqs[j])
        act = set(self._act_v)
        self._free_v = np.array([i for i in range(model.nv) if i not in act], dtype=int)
        self._act_v_arr = np.array(self._act_v, dtype=int)
        self._closure_fids = [
            (self.frame_id(c.frame_a), self.frame_id(c.frame_b)) for c in self.closures
        ]
        self.n_closure_rows = sum(c.size for c in self.closures)
        lower, upper = [], []
        for qi, nq in zip(self._act_q, self._act_nq, strict=True):
            if nq == 1:
                lower.append(model.lowerPositionLimit[qi])
                upper.append(model.upperPositionLimit[qi])
            else:
                lower.append(-np.inf)
                upper.append(np.inf)
        self.actuator_limits = np.array([lower, upper]).T  # (n_act, 2)

    def _resolve_measured_frame(self, requested: str | None) -> str:
        name = requested or self.sidecar.measured_frame
        if name is None:
            # the last link of the URDF in declaration order that is a leaf
            parents = {j.parent for j in self.tree.joints.values()}
            leaves = [link for link in self.tree.links if link not in parents]
            name = leaves[-1] if leaves else self.tree.links[-1]
        self.frame_id(str(name))
        return str(name)

    def _parse_workspace(self) -> Workspace:
        ws = self.sidecar.workspace
        for k in ws.joints:
            if k not in self.actuated:
                raise UnknownNameError("actuated joint", k, self.actuated)
        return Workspace(dict(ws.pose), dict(ws.joints))

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
    def _data(self) -> pin.Data:
        """This thread's scratch ``pin.Data``: filled and read within one call only."""
        data = getattr(self._scratch, "data", None)
        if data is None:
            data = self._scratch.data = self.model.createData()
        return data

    def _compute(self, q: np.ndarray) -> pin.Data:
        """Placements and joint Jacobians at ``q`` in the scratch data."""
        data = self._data()
        pin.computeJointJacobians(self.model, data, q)
        pin.updateFramePlacements(self.model, data)
        return data

    def _closure_residual(self, data: pin.Data) -> np.ndarray:
        if not self.closures:
            return np.zeros(0)
        oMf = data.oMf
        return np.concatenate(
            [
                c.residual(oMf[a], oMf[b])
                for (a, b), c in zip(self._closure_fids, self.closures, strict=True)
            ]
        )

    def _closure_jacobian(self, data: pin.Data) -> np.ndarray:
        if not self.closures:
            return np.zeros((0, self.model.nv))
        oMf = data.oMf
        model, lwa, local = self.model, pin.LOCAL_WORLD_ALIGNED, pin.LOCAL
        blocks = []
        for (a, b), c in zip(self._closure_fids, self.closures, strict=True):
            if c.is_point:  # world-aligned point velocities directly
                Jb = pin.getFrameJacobian(model, data, b, lwa)
                Ja = pin.getFrameJacobian(model, data, a, lwa)
                blocks.append(Jb[:3] - Ja[:3])
            else:
                Ja = pin.getFrameJacobian(model, data, a, local)
                Jb = pin.getFrameJacobian(model, data, b, local)
                blocks.append(c.jacobian(oMf[a], oMf[b], Ja, Jb))
        return np.vstack(blocks)

    def _snapshot(
        self, q: np.ndarray, data: pin.Data, frames: Sequence[str], jacobian_frames: Sequence[str]
    ) -> Kinematics:
        model = self.model
        return Kinematics(
            q=np.array(q, dtype=float),
            placements={f: pin.SE3(data.oMf[self.frame_id(f)]) for f in frames},
            jacobians={
                f: pin.getFrameJacobian(model, data, self.frame_id(f), pin.LOCAL)
                for f in jacobian_frames
            },
            joint_placements=tuple(pin.SE3(M) for M in data.oMi),
            closure_residual=self._closure_residual(data),
            closure_jacobian=self._closure_jacobian(data),
        )

    def kinematics(
        self,
        q: np.ndarray,
        frames: Sequence[str] | None = None,
        jacobian_frames: Sequence[str] | None = None,
    ) -> Kinematics:
        """Kinematics of configuration ``q`` (nq,): a fresh, frozen :class:`Kinematics`.

        Args:
            q: Pinocchio configuration (nq,) (need not close the loops).
            frames: frames whose world placement to keep (default: :attr:`key_frames`,
                the measured frame and every closure frame).
            jacobian_frames: frames whose LOCAL Jacobian to keep (default: the measured
                frame).
        """
        q = self._check_q(q)
        jac = (self.measured_frame,) if jacobian_frames is None else jacobian_frames
        return self._snapshot(q, self._compute(q), frames or self.key_frames, jac)

    def frame_link(self, frame: str) -> str:
        """URDF link a frame is attached to (a frame named by a joint sits on its child)."""
        self.frame_id(frame)
        if frame in self.tree.joints and frame not in self.tree.links:
            return self.tree.joints[frame].child
        return frame

    @property
    def free_dofs(self) -> np.ndarray:
        """Tangent indices (k,) of the passive (not actuated) degrees of freedom."""
        return self._free_v.copy()

    def frame_placement(self, q: np.ndarray, frame: str | None = None) -> pin.SE3:
        """World placement (a new SE3) of ``frame`` (default: the measured frame) at ``q``."""
        q = self._check_q(q)
        fid = self.frame_id(frame or self.measured_frame)
        return pin.SE3(self._compute(q).oMf[fid])

    def closure_residual(self, q: np.ndarray) -> np.ndarray:
        """Closure residual at configuration q (n_closure_rows,) [m, rad]."""
        return self._closure_residual(self._compute(self._check_q(q)))

    def closure_jacobian(self, q: np.ndarray) -> np.ndarray:
        """(n_closure_rows, nv) closure Jacobian at configuration q."""
        return self._closure_jacobian(self._compute(self._check_q(q)))

    def _check_q(self, q: np.ndarray) -> np.ndarray:
        q = np.asarray(q, dtype=float)
        if q.shape != (self.model.nq,):
            raise ValueError(f"q must have shape ({self.model.nq},), got {q.shape}")
        return q

    def _newton(self, q0: np.ndarray, free: np.ndarray, extra=None) -> _Solution:
        """Damped Newton on the closure (+ optional extra) residual over tangent dofs ``free``.

        ``extra`` is a callable of the computed data returning ``(r (k,), J (k, nv))``.
        """
        opt = self.options
        q = q0.copy()
        nv = self.model.nv

        extra_jacobian = [np.zeros((0, nv))]

        data = self._data()

        def evaluate(qq):
            self._compute(qq)
            r = self._closure_residual(data)
            if extra is not None:
                r_extra, extra_jacobian[0] = extra(data)
                r = np.concatenate([r, r_extra])
            return r

        r = evaluate(q)
        norm = np.linalg.norm(r)
        for it in range(opt.max_iterations + 1):
            J = self._closure_jacobian(data)
            if extra is not None:
                J = np.vstack([J, extra_jacobian[0]])
            Jf = J[:, free]
            if np.max(np.abs(r), initial=0.0) <= opt.tol:
                s = np.linalg.svd(Jf, compute_uv=False) if Jf.size else np.zeros(0)
                return _Solution(q, it, float(np.max(np.abs(r), initial=0.0)), s)
            if it == opt.max_iterations:
                break
            step = _newton_step(Jf, r, opt.rcond)
            step_norm = np.linalg.norm(step)
            if step_norm > opt.max_step:
                step *= opt.max_step / step_norm
            dv = np.zeros(nv)
            dv[free] = step
            alpha = 1.0
            for _ in range(30):
                q_try = pin.integrate(self.model, q, alpha * dv)
                r_try = evaluate(q_try)
                n_try = np.linalg.norm(r_try)
                if n_try < norm or n_try <= opt.tol:
                    break
                alpha *= 0.5
            else:  # no decrease along the Newton direction: stalled
                break
            q, r, norm = q_try, r_try, n_try
        raise ConvergenceError(
            f"Newton did not converge: residual {np.max(np.abs(r)):.3e} after {it} iterations",
            residual=float(np.max(np.abs(r))),
        )

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
    @property
    def n_actuated(self) -> int:
        return len(self.actuated)

    def actuators_of(self, q: np.ndarray) -> np.ndarray:
        """Actuated joint values (n_act,) of a configuration q (nq,)."""
        out = np.empty(len(self.actuated))
        for k, (qi, nq) in enumerate(zip(self._act_q, self._act_nq, strict=True)):
            out[k] = q[qi] if nq == 1 else np.arctan2(q[qi + 1], q[qi])
        return out

    def with_actuators(self, q: np.ndarray, q_act: np.ndarray) -> np.ndarray:
        """Copy of configuration q with the actuated joints set to ``q_act``."""
        q = np.array(q, dtype=float)
        for v, qi, nq in zip(q_act, self._act_q, self._act_nq, strict=True):
            if nq == 1:
                q[qi] = v
            else:
                q[qi : qi + 2] = (np.cos(v), np.sin(v))
        return q

    def _check_q_act(self, q_act: np.ndarray) -> np.ndarray:
        q_act = np.asarray(q_act, dtype=float)
        if q_act.shape != (len(self.actuated),):
            raise ValueError(
                f"q_act must have shape ({len(self.actuated)},) for actuated joints "
                f"{list(self.actuated)}, got {q_act.shape}"
            )
        return q_act

    def configuration(
        self, q_act: np.ndarray, q_guess: np.ndarray | None = None, pose_index: int | None = None
    ) -> np.ndarray:
        """Full configuration (nq,) with loops closed for actuator values ``q_act``.

        Raises:
            ConvergenceError: the loops cannot be closed from the guess.
            SingularConfigurationError: the passive joints are not locally unique.
        """
        q_act = self._check_q_act(q_act)
        guess = self.q_home if q_guess is None else q_guess
        q0 = self.with_actuators(guess, q_act)
        if not self.closures:
            return q0
        where = f"pose {pose_index}" if pose_index is not None else "pose"
        try:
            sol = self._newton(q0, self._free_v)
        except ConvergenceError as exc:
            raise ConvergenceError(
                f"forward kinematics failed at {where} (q_act = {np.round(q_act, 6).tolist()}): "
                f"loops do not close, residual {exc.residual * 1e3:.3g} mm",
                pose_index=pose_index,
                residual=exc.residual,
            ) from exc
        self._check_singular(sol, where, pose_index)
        return sol.q

    def _check_singular(self, sol: _Solution, where: str, pose_index: int | None) -> None:
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

    def forward(self, q_act: np.ndarray, q_guess: np.ndarray | None = None) -> pin.SE3:
        """Pose of the measured frame in the world for actuator values ``q_act``."""
        return self.frame_placement(self.configuration(q_act, q_guess))

    def configurations(self, q_act_rows: np.ndarray) -> np.ndarray:
        """Closed configurations (m, nq) for actuator rows (m, n_act), warm-started."""
        rows = np.atleast_2d(np.asarray(q_act_rows, dtype=float))
        out = np.empty((rows.shape[0], self.model.nq))
        guess = self.q_home
        for i, row in enumerate(rows):
            try:
                out[i] = self.configuration(row, guess, pose_index=i)
            except SingularConfigurationError:
                raise
            except ConvergenceError:
                out[i] = self.configuration(row, self.q_home, pose_index=i)
            guess = out[i]
        return out

    def inverse(
        self, T_world_target: pin.SE3, q_guess: np.ndarray | None = None, check_limits: bool = True
    ) -> np.ndarray:
        """Actuator values (n_act,) that bring the measured frame to ``T_world_target``.

        Only the measured components are imposed (e.g. position only for a CMM arm).

        Raises:
            UnreachablePoseError: no convergence, or actuators outside their limits.
        """
        q = self.inverse_configuration(T_world_target, q_guess)
        q_act = self.actuators_of(q)
        if check_limits:
            lo, hi = self.actuator_limits.T
            bad = np.nonzero((q_act < lo - 1e-12) | (q_act > hi + 1e-12))[0]
            if bad.size:
                k = int(bad[0])
                raise UnreachablePoseError(
                    f"target pose needs joint {self.actuated[k]!r} = {q_act[k]:.6g}, outside "
                    f"its limits [{lo[k]:.6g}, {hi[k]:.6g}]"
                )
        return q_act

    def inverse_configuration(
        self, T_world_target: pin.SE3, q_guess: np.ndarray | None = None
    ) -> np.ndarray:
        """Full closed configuration (nq,) reaching the target (see :meth:`inverse`)."""
        fid = self.frame_id(self.measured_frame)
        comps = np.array([COMPONENTS.index(c) for c in self.measured_components])
        target_p, target_R = T_world_target.translation, T_world_target.rotation

        def extra(data: pin.Data) -> tuple[np.ndarray, np.ndarray]:
            oMf = data.oMf[fid]
            r = np.zeros(6)
            r[:3] = oMf.translation - target_p
            E = target_R.T @ oMf.rotation
            r[3:] = pin.log3(E)
            J = measured_jacobian(oMf, pin.getFrameJacobian(self.model, data, fid, pin.LOCAL))
            J[3:] = pin.Jlog3(E) @ J[3:]
            return r[comps], J[comps]

        guess = self.q_home if q_guess is None else q_guess
        try:
            sol = self._newton(guess, np.arange(self.model.nv), extra)
        except ConvergenceError as exc:
            raise UnreachablePoseError(
                f"target pose unreachable (p = {np.round(target_p * 1e3, 3).tolist()} mm): "
                f"residual {exc.residual * 1e3:.3g} mm/mrad after Newton",
                residual=exc.residual,
            ) from exc
        return sol.q


def _read_text(path: Path, what: str) -> str:
    try:
        return path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ModelFileError(f"cannot read {what} {str(path)!r}: {exc.strerror}") from exc


def read_sidecar(path: Path) -> dict[str, Any]:
    """Parse a sidecar YAML file safely (no code execution)."""
    try:
        data = yaml.safe_load(_read_text(path, "sidecar"))
    except yaml.YAMLError as exc:
        raise ModelFileError(f"sidecar {str(path)!r} is not valid YAML: {exc}") from exc
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise ModelFileError(f"sidecar {str(path)!r} must be a mapping, got {type(data).__name__}")
    return data


def bundled_models() -> list[str]:
    """Names of the models shipped in ``models/``."""
    if not MODELS_DIR.is_dir():
        return []
    return sorted(p.name for p in MODELS_DIR.iterdir() if (p / f"{p.name}.urdf").is_file())


def resolve_model_path(spec: str | Path) -> tuple[Path, Path | None]:
    """Find the URDF (and sidecar, if any) for a model directory, URDF path, bundled
    model name or example-robot-data robot name (e.g. ``ur10``)."""
    path = Path(spec)
    if path.is_dir():
        urdf = path / f"{path.name}.urdf"
        if not urdf.is_file():
            candidates = sorted(path.glob("*.urdf"))
            if len(candidates) != 1:
                raise ModelFileError(f"model directory {str(path)!r} must hold {path.name}.urdf")
            urdf = candidates[0]
    elif path.suffix.lower() == ".urdf":
        urdf = path
        if not urdf.is_file():
            raise ModelFileError(f"URDF file {str(path)!r} does not exist")
    elif (MODELS_DIR / str(spec)).is_dir():
        return resolve_model_path(MODELS_DIR / str(spec))
    else:
        from pincal.model._dh import example_robot_names, example_robot_urdf

        if str(spec) not in example_robot_names():
            valid = bundled_models() + [f"{n} (example-robot-data)" for n in example_robot_names()]
            raise UnknownNameError("model", str(spec), valid)
        urdf = example_robot_urdf(str(spec))
    sidecar = urdf.with_suffix(".yaml")
    return urdf, sidecar if sidecar.is_file() else None


def load_mechanism(
    spec: str | Path, measured_frame: str | None = None, options: SolverOptions | None = None
) -> Mechanism:
    """Load a mechanism from a model directory, a ``.urdf`` path or a bundled model name.

    A sidecar ``<name>.yaml`` beside the URDF declares closures, actuation, measured
    frame and presets (see models/README.md). A bare serial URDF needs none: all its
    1-dof joints are actuated and its last leaf link is the measured frame.

    Raises:
        ModelFileError, UnknownNameError, ClosureError, MobilityError.
    """
    urdf, sidecar_path = resolve_model_path(spec)
    sidecar = read_sidecar(sidecar_path) if sidecar_path else {}
    return Mechanism(
        _read_text(urdf, "URDF"),
        sidecar,
        name=urdf.stem,
        source=urdf,
        measured_frame=measured_frame,
        options=options,
    )
