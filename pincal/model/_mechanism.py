"""Mechanism: a URDF spanning tree, its loop closures, actuation and measured frame.

A :class:`Mechanism` is immutable: applying parameter values or calibrating returns a
new one. Configuration vectors ``q`` are Pinocchio configurations (size ``nq``;
quaternions are x, y, z, w); actuator vectors ``q_act`` hold one value per actuated
joint in the order of :attr:`Mechanism.actuated` [m or rad].
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from pincal.errors import (
    ConvergenceError,
    ModelFileError,
    ShapeError,
    UnknownNameError,
    UnreachablePoseError,
)
from pincal.model._batch_fk import BatchTracking
from pincal.model._build import build_model, lock_joints
from pincal.model._closures import (
    COMPONENTS,
    Closure,
    measured_jacobian,
    parse_components,
)
from pincal.model._frames import default_measured_frame, measured_frame_candidates
from pincal.model._kinematics import Kinematics
from pincal.model._newton import SolverOptions
from pincal.model._sidecar import WORKSPACE_POSE_KEYS, Sidecar, Workspace
from pincal.model._urdf import UrdfTree

__all__ = [
    "WORKSPACE_POSE_KEYS",
    "Kinematics",
    "Mechanism",
    "Sidecar",
    "SolverOptions",
    "Workspace",
]

log = logging.getLogger(__name__)


class Mechanism(BatchTracking):
    """A mechanism loaded from URDF (+ sidecar).

    Use :func:`load_mechanism` to create one. Attributes of interest:

    * ``model``: the Pinocchio model (do not modify);
    * ``actuated``: actuated joint names; ``closures``: the loop closures;
    * ``measured_frame`` and ``measured_components`` (names from x y z rx ry rz);
    * ``q_home``: assembled home configuration (nq,); forward kinematics stays on its
      assembly mode (``home_branch``: sign of det of the passive closure Jacobian, 0
      where that Jacobian is not square; ``idle_branch``: the same sign with idle passive
      directions left out, see ``_branch``); ``batch_solvable``: whether
      :meth:`configurations_batch` closes the loops of many poses together;
    * ``workspace``: :class:`Workspace`; ``presets``: raw parameter presets;
    * ``sidecar``: the typed :class:`Sidecar`; ``notes``: remarks for ``pincal info``;
    * ``mobility``, ``closure_rank`` and ``idle_joints`` (passive joints the actuators
      do not hold and that do not move the measured frame).

    ``tree`` passes the already parsed :class:`UrdfTree` of ``urdf_xml`` (as
    :meth:`UrdfTree.displaced` returns it), so that the text is not parsed and checked
    again; it must be the tree of exactly that text.
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
        tree: UrdfTree | None = None,
    ):
        self.sidecar: Sidecar = Sidecar.from_dict(sidecar)
        self.urdf_xml, self.tree = lock_joints(
            urdf_xml, UrdfTree(urdf_xml) if tree is None else tree, self.sidecar
        )
        self.name = name or self.tree.name
        self.source = source
        self.options = options or SolverOptions()
        model, notes = build_model(self.urdf_xml, self.tree, self.sidecar)
        self.model = model
        #: remarks about the model (joint kinds from the sidecar, ranges), for `pincal info`
        self.notes: tuple[str, ...] = tuple(notes)
        self._scratch = threading.local()  # per-thread pin.Data, never read across calls
        self._frame_ids = {f.name: i for i, f in enumerate(self.model.frames)}
        self.closures = self._parse_closures()
        self.measured_frame = self._resolve_measured_frame(measured_frame)
        self.actuated = self._parse_actuated()
        self._setup_indices()
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
        self._assembly_notes: list[str] = []
        if q_guess is None:
            keep = any(n in self.sidecar.home for n in self.actuated)
            self.q_home = self._assemble(self._home_guess(), keep_actuators=keep)
        else:
            self.q_home = self._assemble(np.asarray(q_guess, dtype=float))
        self.notes += tuple(self._assembly_notes)
        self._check_mobility()
        self._init_branch()

    # ------------------------------------------------------------------ set-up
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
            return self._chain_joints(movable)
        for n in names:
            if n not in movable:
                raise UnknownNameError("actuated joint", str(n), movable)
        if len(set(names)) != len(names):
            raise ModelFileError(f"sidecar 'name_mot' lists a joint twice: {names}")
        return tuple(str(n) for n in names)

    def _chain_joints(self, movable: list[str]) -> tuple[str, ...]:
        """An open chain's actuated joints: the 1-dof joints that move the measured frame.

        The others (a gripper's fingers, a mobile manipulator's head) stay passive and
        idle: they are not actuated for calibration, and a note says so.
        """
        model = self.model
        support = set(model.supports[model.frames[self.frame_id(self.measured_frame)].parentJoint])
        chain = tuple(n for n in movable if model.getJointId(n) in support)
        off = [n for n in movable if n not in chain]
        if off:
            shown = ", ".join(off[:6]) + (f" and {len(off) - 6} more" if len(off) > 6 else "")
            self.notes += (
                f"{len(off)} joint(s) do not move the measured frame {self.measured_frame!r} and "
                f"are not actuated for calibration: {shown} (list the actuated joints in the "
                f"sidecar 'name_mot' to change this)",
            )
        return chain

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
            name = default_measured_frame(self.tree, self._closure_links(), self.name)
        self.frame_id(str(name))
        return str(name)

    def _closure_links(self) -> set[str]:
        return {self.frame_link(f) for c in self.closures for f in (c.frame_a, c.frame_b)}

    @property
    def measured_frame_candidates(self) -> list[str]:
        """Frames the automatic choice would consider, best first (see ``_frames``)."""
        return measured_frame_candidates(self.tree, self._closure_links())

    def _parse_workspace(self) -> Workspace:
        ws = self.sidecar.workspace
        for k in ws.joints:
            if k not in self.actuated:
                raise UnknownNameError("actuated joint", k, self.actuated)
        return Workspace(dict(ws.pose), dict(ws.joints), ws.floor)

    def configuration(
        self, q_act: np.ndarray, q_guess: np.ndarray | None = None, pose_index: int | None = None
    ) -> np.ndarray:
        """Full configuration (nq,) with loops closed for actuator values ``q_act``.

        The solution stays on the assembly mode of :attr:`q_home` (see ``_branch``):
        a solve from ``q_guess`` (default home) that fails or lands on another branch is
        redone from home, then by continuation from the guess, then from home.

        Raises:
            ConvergenceError: no solution on the home branch (the message names the pose).
            SingularConfigurationError: the passive joints are not locally unique.
        """
        q_act = self._check_q_act(q_act)
        guess = self.q_home if q_guess is None else self._check_q(q_guess)
        if not self.closures:
            return self.with_actuators(guess, q_act)
        where = f"pose {pose_index}" if pose_index is not None else "pose"
        try:
            sol = self._solve_on_branch(q_act, guess)
        except ConvergenceError as exc:
            raise ConvergenceError(
                f"forward kinematics failed at {where} (q_act = {np.round(q_act, 6).tolist()}): "
                f"the loops do not close on the assembly branch of home (residual "
                f"{exc.residual * 1e3:.3g} mm); {exc}",
                pose_index=pose_index,
                residual=exc.residual,
            ) from exc
        self._check_singular(sol, where, pose_index)
        return sol.q

    def forward(self, q_act: np.ndarray, q_guess: np.ndarray | None = None) -> pin.SE3:
        """Pose of the measured frame in the world for actuator values ``q_act``."""
        return self.frame_placement(self.configuration(q_act, q_guess))

    def configurations(self, q_act_rows: np.ndarray) -> np.ndarray:
        """Closed configurations (m, nq) for actuator rows (m, n_act) on home's branch.

        All rows are solved together from home (:meth:`configurations_batch`); a row the
        batched Newton does not settle is redone pose by pose from home, as
        :meth:`configuration` closes it (continuation when a direct solve leaves the
        branch).
        """
        return self.configurations_batch(q_act_rows)[0]

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
        T_world_target = _as_se3(T_world_target)
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

        guess = self.q_home if q_guess is None else self._check_q(q_guess)
        try:
            sol = self._newton(guess, np.arange(self.model.nv), extra)
        except ConvergenceError as exc:
            raise UnreachablePoseError(
                f"target pose unreachable (p = {np.round(target_p * 1e3, 3).tolist()} mm): "
                f"residual {exc.residual * 1e3:.3g} mm/mrad after Newton"
                + self._dead_start_note(guess, fid, comps),
                residual=exc.residual,
            ) from exc
        if self.idle_branch and self._branch_sign(sol.q) != self.idle_branch:
            raise UnreachablePoseError(
                f"target pose (p = {np.round(target_p * 1e3, 3).tolist()} mm) is reached only in "
                f"another assembly mode than home's: forward kinematics would not return it; "
                f"give q_guess on home's mode or choose another target",
                residual=0.0,
            )
        return sol.q

    def _output_rank(self, q: np.ndarray, fid: int, comps: np.ndarray) -> int:
        """Rank of the actuator → measured-components map at q, the loops staying closed."""
        data = self._compute(q)
        J_frame = pin.getFrameJacobian(self.model, data, fid, pin.LOCAL)
        Jm = measured_jacobian(data.oMf[fid], J_frame)[comps]
        Jc = self._closure_jacobian(data)
        act, free = self._act_v_arr, self._free_v
        dq_free = -np.linalg.pinv(Jc[:, free], rcond=self.options.rcond) @ Jc[:, act]
        G = Jm[:, act] + Jm[:, free] @ dq_free
        s = np.linalg.svd(G, compute_uv=False)
        scale = max(float(np.max(np.abs(Jm), initial=0.0)), 1e-300)
        return int(np.sum(s > 1e-9 * scale))

    def _dead_start_note(self, q: np.ndarray, fid: int, comps: np.ndarray) -> str:
        """Why inverse kinematics may not leave ``q`` ("" when it is not a dead point).

        A dead point: the actuators move the measured components in fewer directions at
        q than at nearby configurations (first order, the loops staying closed).
        """
        rank = self._output_rank(q, fid, comps)
        rng = np.random.default_rng(0)
        nearby = max(
            self._output_rank(
                pin.integrate(self.model, q, 1e-3 * rng.standard_normal(self.model.nv)), fid, comps
            )
            for _ in range(3)
        )
        if rank >= nearby:
            return ""
        return (
            f". At the start configuration the actuators {list(self.actuated)} move the "
            f"measured components {list(self.measured_components)} in only {rank} "
            f"independent direction(s) at first order, {nearby} nearby (a dead point of the "
            f"output): Newton cannot leave it, and nearby targets are reached by several "
            f"actuator values (e.g. a mirror-symmetric machine). Give q_guess near the "
            f"solution, or put the sidecar 'home' away from the dead point and keep the "
            f"workspace on one side of it"
        )


def _as_se3(T: object) -> pin.SE3:
    """A pin.SE3, or a (4, 4) homogeneous matrix turned into one."""
    if isinstance(T, pin.SE3):
        return T
    try:
        M = np.asarray(T, dtype=float)
    except (TypeError, ValueError):
        M = np.zeros(0)
    if M.shape != (4, 4) or not np.all(np.isfinite(M)):
        raise ShapeError(
            f"target pose must be a pinocchio.SE3 or a finite (4, 4) matrix, got {type(T).__name__}"
            f"{' of shape ' + str(M.shape) if M.size else ''}"
        )
    R = M[:3, :3]
    if not np.allclose(R.T @ R, np.eye(3), atol=1e-9) or np.linalg.det(R) < 0:
        raise ShapeError("target pose matrix: the upper-left (3, 3) block must be a rotation")
    return pin.SE3(R, M[:3, 3])
