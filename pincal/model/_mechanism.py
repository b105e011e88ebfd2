"""Mechanism: a URDF spanning tree, its loop closures, actuation and measured frame.

Applying parameter values or calibrating returns a new mechanism derived from this one
(:meth:`Mechanism.with_joint_origins`: the origins written into a copy of the Pinocchio
model, the description shared); a mechanism is not modified after it is made, and
assigning or deleting an attribute raises :class:`~pincal.errors.ImmutableError` (see
``_read_only``).
Configuration vectors ``q`` are Pinocchio configurations (size ``nq``; quaternions are
x, y, z, w); actuator vectors ``q_act`` hold one value per actuated joint in the order of
:attr:`Mechanism.actuated` [m or rad].

The mechanism is the description (model, frames, actuation, closures, workspace); it
owns its single-pose kinematic queries, a pose-by-pose loop solver and a batched loop
solver, each built from explicit arguments, and delegates to them.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Literal, overload

import numpy as np
import pinocchio as pin

from pincal.model._description import (
    actuator_limits,
    closure_links,
    parse_actuated,
    parse_closures,
    parse_workspace,
    resolve_measured_frame,
)
from pincal.model._loop_parts import close_loops
from pincal.model._placements import PlacementTree
from pincal.model._read_only import ReadOnly, derivation
from pincal.model.batch import BatchKinematics, BatchModel, PassiveFactor
from pincal.model.files import (
    COMPONENTS,
    Sidecar,
    UrdfTree,
    build_model,
    lock_joints,
    measured_frame_candidates,
    parse_components,
)
from pincal.model.loops import (
    REDUNDANT_RTOL,
    KinematicQueries,
    Kinematics,
    SolverOptions,
    check_actuator_limits,
    inverse_configuration,
    model_size,
)

__all__ = ["Mechanism"]


class Mechanism(ReadOnly):
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
    * ``queries`` (:class:`~pincal.model.loops._kinematics.KinematicQueries`: single-pose
      kinematics), ``loop_solver`` (:class:`~pincal.model.loops._branch.LoopSolver`: pose by
      pose) and ``batch_solver`` (:class:`~pincal.model.batch._batch_fk.BatchLoopSolver`):
      the parts it owns: a query the mechanism offers is asked of the mechanism (one
      way in), a part only for what the mechanism does not offer;
    * ``workspace``: :class:`~pincal.model.files.Workspace`; ``presets``: raw parameter
      presets;
    * ``sidecar``: the typed :class:`Sidecar`; ``notes``: remarks for ``pincal info``;
    * ``mobility``, ``closure_rank`` and ``idle_joints`` (passive joints the actuators
      do not hold and that do not move the measured frame).

    ``tree`` passes the already parsed :class:`UrdfTree` of ``urdf_xml`` (as
    :meth:`UrdfTree.displaced` returns it), so that the text is not parsed and checked
    again; it must be the tree of exactly that text.

    Read-only: assigning or deleting an attribute raises
    :class:`~pincal.errors.ImmutableError`; values other modules compute from a
    mechanism are kept by :meth:`memo`.
    """

    DERIVE_HINT = (
        "derive a new one instead: with_joint_origins(...) for moved joints, "
        "load_mechanism(..., options=..., measured_frame=...) for other settings, or edit "
        "the sidecar / URDF and load again"
    )

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
        urdf_xml, self.tree = lock_joints(
            urdf_xml, UrdfTree(urdf_xml) if tree is None else tree, self.sidecar
        )
        self._urdf_xml: str | None = urdf_xml
        self.name = name or self.tree.name
        self.source = source
        self.options = options or SolverOptions()
        model, notes = build_model(urdf_xml, self.tree, self.sidecar)
        if self.options.redundant_tol is None:  # least-squares closures: scaled to the model
            self.options = dataclasses.replace(
                self.options, redundant_tol=REDUNDANT_RTOL * model_size(model)
            )
        frame_ids = {f.name: i for i, f in enumerate(model.frames)}
        self.closures = parse_closures(self.sidecar, frame_ids, self.tree)
        self.measured_frame = resolve_measured_frame(
            measured_frame, self.sidecar, self.tree, self.closures, frame_ids, self.name
        )
        self.actuated, chain_notes = parse_actuated(
            model, self.sidecar, self.closures, frame_ids, self.measured_frame
        )
        self._model_notes = (*notes, *chain_notes)
        self.measured_components = tuple(
            COMPONENTS[i] for i in parse_components(self.sidecar.measured, "sidecar 'measured'")
        )
        self.presets: dict[str, Any] = dict(self.sidecar.presets)
        self.workspace = parse_workspace(self.sidecar, self.actuated)
        self._placements = PlacementTree(model)
        self._close(model, frame_ids, q_guess)
        self.actuator_limits = actuator_limits(model, self.queries)  # (n_act, 2)
        self.actuator_limits.setflags(write=False)
        self.freeze()

    def _close(
        self,
        model: pin.Model,
        frame_ids: dict[str, int],
        q_guess: np.ndarray | None,
        moved_from: tuple[Mechanism, set[int], set[int]] | None = None,
    ) -> None:
        """Take ``model`` as this mechanism's model: its queries, home, mobility, solvers.

        ``moved_from``: the mechanism whose model ``model`` was moved from (same tree),
        the ids of the joints and the indices of the frames that moved: its batched
        kinematics and scratch data serve as templates (see ``_loop_parts``).
        """
        self.model = model
        self.queries: KinematicQueries = KinematicQueries(
            model, self.tree, self.name, frame_ids, self.closures, self.actuated,
            self.measured_frame, None if moved_from is None else moved_from[0].queries,
        )  # fmt: skip
        #: the frames a sensitivity needs: the measured frame and every closure frame
        self.key_frames = self.queries.key_frames
        self.n_closure_rows = self.queries.n_closure_rows
        template = None if moved_from is None else (moved_from[0].batch_model, *moved_from[1:])
        parts = close_loops(self.queries, self.options, self.sidecar.home, q_guess, template)
        self.q_home, self.mobility = parts.q_home, parts.mobility
        self.closure_rank, self.idle_joints = parts.closure_rank, parts.idle_joints
        #: remarks about the model (joint kinds from the sidecar, ranges), for `pincal info`
        self.notes: tuple[str, ...] = (*self._model_notes, *parts.notes)
        self.loop_solver, self.batch_solver = parts.loop_solver, parts.batch_solver
        self.home_branch = self.loop_solver.home_branch
        #: the branch sign of the square block of rank rows and non-idle columns
        #: (= home_branch when the passive closure Jacobian is square; 0: no branch)
        self.idle_branch = self.loop_solver.idle_branch

    @property
    def urdf_xml(self) -> str:
        """The URDF text of this mechanism (written on first use for a derived one)."""
        return self.memo("urdf_xml", self.tree.text) if self._urdf_xml is None else self._urdf_xml

    def with_joint_origins(self, origins: Mapping[str, pin.SE3]) -> Mechanism:
        """A new mechanism with URDF joint origins replaced (this one is not modified).

        Derived, not rebuilt: the origins are written into a copy of the Pinocchio model
        (:class:`~pincal.model._placements.PlacementTree`) and the tree; the
        description (sidecar, name, source, measured frame, actuation, closures,
        workspace, solver options) is shared; the loops are closed from this mechanism's
        home (on its assembly mode) and the mobility checked there. The URDF text is
        written only when asked for.

        Args:
            origins: joint name → new origin placement (parent link → joint frame) [m].

        Raises:
            UnknownNameError: an origin names a joint the URDF does not have.
            ClosureError, MobilityError, SingularConfigurationError: the moved geometry
                does not assemble, or not with this mobility.
        """
        tree = self.tree.moved(origins)
        moves = {j: self.tree.joints[j].origin.actInv(tree.joints[j].origin) for j in origins}
        new = derivation(self)
        new.tree, new._urdf_xml = tree, None
        model, joints, frames = self._placements.moved(self.model, moves)
        new._close(model, self.queries.frame_ids, self.q_home, (self, joints, frames))
        new.freeze()
        return new

    def with_notes(self, before: Sequence[str] = (), after: Sequence[str] = ()) -> Mechanism:
        """This mechanism with remarks added before / after its :attr:`notes`.

        For loaders that say what they did to a file (locked joints, a home searched
        nearby); everything else is shared (this one is not modified).
        """
        new = derivation(self)
        new.notes = (*before, *self.notes, *after)
        new.freeze()
        return new

    @property
    def measured_frame_candidates(self) -> list[str]:
        """Frames the automatic choice would consider, best first (see ``_frames``)."""
        return measured_frame_candidates(self.tree, closure_links(self.tree, self.closures))

    # ------------------------------------------------- single-pose queries (delegated)
    def frame_id(self, name: str) -> int:
        """Pinocchio frame index of a frame (URDF link or joint) by name."""
        return self.queries.frame_id(name)

    def joint_id(self, name: str) -> int:
        """Pinocchio joint index of a joint by name."""
        return self.queries.joint_id(name)

    def frame_link(self, frame: str) -> str:
        """URDF link a frame is attached to (a frame named by a joint sits on its child)."""
        return self.queries.frame_link(frame)

    @property
    def free_dofs(self) -> np.ndarray:
        """Tangent indices (k,) of the passive (not actuated) degrees of freedom."""
        return self.queries.free_dofs

    @property
    def n_actuated(self) -> int:
        """Number of actuated joints."""
        return len(self.actuated)

    def kinematics(
        self,
        q: np.ndarray,
        frames: Sequence[str] | None = None,
        jacobian_frames: Sequence[str] | None = None,
    ) -> Kinematics:
        """Kinematics of configuration ``q`` (nq,) (see :meth:`KinematicQueries.kinematics`)."""
        return self.queries.kinematics(q, frames, jacobian_frames)

    def frame_placement(self, q: np.ndarray, frame: str | None = None) -> pin.SE3:
        """World placement (a new SE3) of ``frame`` (default: the measured frame) at ``q``."""
        return self.queries.frame_placement(q, frame)

    def closure_residual(self, q: np.ndarray) -> np.ndarray:
        """Closure residual at configuration q (n_closure_rows,) [m, rad]."""
        return self.queries.closure_residual(q)

    def closure_jacobian(self, q: np.ndarray) -> np.ndarray:
        """(n_closure_rows, nv) closure Jacobian at configuration q."""
        return self.queries.closure_jacobian(q)

    def actuators_of(self, q: np.ndarray) -> np.ndarray:
        """Actuated joint values (n_act,) of a configuration q (nq,)."""
        return self.queries.actuators_of(q)

    def with_actuators(self, q: np.ndarray, q_act: np.ndarray) -> np.ndarray:
        """Copy of configuration q with the actuated joints set to ``q_act``."""
        return self.queries.with_actuators(q, q_act)

    # ------------------------------------------------------- loop closing (delegated)
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
        return self.loop_solver.configuration(q_act, q_guess, pose_index)

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

    def configurations_batch(
        self, q_act_rows: np.ndarray, guesses: np.ndarray | None = None
    ) -> tuple[np.ndarray, BatchKinematics | None]:
        """Closed configurations (N, nq) on home's branch and their kinematics.

        See :meth:`BatchLoopSolver.configurations_batch
        <pincal.model.batch._batch_fk.BatchLoopSolver.configurations_batch>`.
        """
        return self.batch_solver.configurations_batch(q_act_rows, guesses)

    def try_configurations_batch(
        self, q_act_rows: np.ndarray, guesses: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray, BatchKinematics | None]:
        """Batched Newton only: configurations (N, nq), accepted mask (N,), kinematics."""
        return self.batch_solver.try_configurations_batch(q_act_rows, guesses)

    def closable_batch(self, q_act_rows: np.ndarray) -> np.ndarray:
        """Whether each actuator row (N, n_act) closes on home's branch (N,) bool."""
        return self.batch_solver.closable_batch(q_act_rows)

    @property
    def batch_solvable(self) -> bool:
        """Whether the batched loop closing applies (else poses are closed one by one)."""
        return self.batch_solver.batch_solvable

    # ------------------------------------------------ batched kernels (delegated)
    @property
    def batch_model(self) -> BatchModel:
        """The batched numpy kinematics of :attr:`model` (built once)."""
        return self.batch_solver.kernels.batch_model

    def kinematics_batch(self, qs: np.ndarray) -> BatchKinematics:
        """Joint placements and WORLD joint Jacobian of configurations ``qs`` (N, nq)."""
        return self.batch_solver.kernels.kinematics_batch(qs)

    def passive_factor(self, Jf: np.ndarray) -> PassiveFactor:
        """Factor passive closure Jacobians ``Jf`` (N, rows, k)."""
        return self.batch_solver.kernels.passive_factor(Jf)

    @overload
    def closure_terms_batch(
        self,
        bk: BatchKinematics,
        jacobian: Literal[True] = ...,
        columns: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray]: ...

    @overload
    def closure_terms_batch(
        self, bk: BatchKinematics, jacobian: bool, columns: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray | None]: ...

    def closure_terms_batch(
        self, bk: BatchKinematics, jacobian: bool = True, columns: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """Closure residuals (N, n_closure_rows) and Jacobians (N, n_closure_rows, nv)."""
        return self.batch_solver.kernels.closure_terms_batch(bk, jacobian, columns)

    # ------------------------------------------------------------ inverse kinematics
    def inverse(
        self, T_world_target: pin.SE3, q_guess: np.ndarray | None = None, check_limits: bool = True
    ) -> np.ndarray:
        """Actuator values (n_act,) that bring the measured frame to ``T_world_target``.

        Only the measured components are imposed (e.g. position only for a CMM arm).

        Raises:
            UnreachablePoseError: no convergence, or actuators outside their limits.
        """
        q_act = self.actuators_of(self.inverse_configuration(T_world_target, q_guess))
        if check_limits:
            check_actuator_limits(q_act, self.actuator_limits, self.actuated)
        return q_act

    def inverse_configuration(
        self, T_world_target: pin.SE3, q_guess: np.ndarray | None = None
    ) -> np.ndarray:
        """Full closed configuration (nq,) reaching the target (see :meth:`inverse`)."""
        return inverse_configuration(
            self.loop_solver, self.measured_components, T_world_target, q_guess
        )
