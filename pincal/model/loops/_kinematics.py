"""Kinematic queries of a mechanism at a given configuration (no shared state).

:class:`KinematicQueries` evaluates placements, Jacobians and closure residuals of a
Pinocchio model with loop closures at a configuration ``q``; each call fills a
per-thread scratch ``pin.Data`` and returns fresh arrays. It is built from explicit
arguments (the model, its frames, closures and actuated joints) by
:class:`~pincal.model.Mechanism`, and shared by its loop solvers.
"""

from __future__ import annotations

import threading
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pincal.errors import ShapeError, UnknownNameError
from pincal.model.files import Closure, UrdfTree
from pincal.model.loops._jacobian_shape import six_by_nv

__all__ = ["KinematicQueries", "Kinematics", "frame_index"]


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


def _as_floats(x: object, what: str) -> np.ndarray:
    try:
        return np.asarray(x, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ShapeError(f"{what} must be an array of numbers: {exc}") from exc


def frame_index(frame_ids: Mapping[str, int], tree: UrdfTree, name: str) -> int:
    """Pinocchio frame index of ``name`` in ``frame_ids`` (name → index).

    Raises:
        UnknownNameError: no such frame (the URDF links are listed).
    """
    if name not in frame_ids:
        raise UnknownNameError("frame", name, tree.links)
    return frame_ids[name]


class KinematicQueries:
    """Configuration-in, fresh-arrays-out queries of a model with loop closures.

    Args:
        model: the Pinocchio model (not modified).
        tree: the parsed URDF the model was built from.
        name: the mechanism name (for messages).
        frame_ids: frame name → Pinocchio frame index.
        closures: the loop closures (their frames exist in ``frame_ids``).
        actuated: actuated joint names (1-dof joints of ``model``).
        measured_frame: the measured frame.
        same_tree: queries of a model of the same tree (a model moved from it, see
            :mod:`~pincal.model._placements`): their per-thread scratch data is shared
            (a ``pin.Data`` depends on the tree only, and is filled and read within one
            call).

    Attributes (besides the arguments):
        key_frames: the measured frame and every closure frame, in that order.
        n_closure_rows: number of closure residual rows.
        closure_fids: (frame a, frame b) Pinocchio indices of each closure.
        act_q, act_v, act_nq: configuration index, tangent index and nq of each actuator.
        act_v_arr: (n_act,) tangent indices of the actuators.
        free_v: (k,) tangent indices of the passive degrees of freedom.
    """

    def __init__(
        self,
        model: pin.Model,
        tree: UrdfTree,
        name: str,
        frame_ids: Mapping[str, int],
        closures: tuple[Closure, ...],
        actuated: tuple[str, ...],
        measured_frame: str,
        same_tree: KinematicQueries | None = None,
    ):
        self.model, self.tree, self.name = model, tree, name
        self.frame_ids = dict(frame_ids)
        self.closures, self.actuated, self.measured_frame = closures, actuated, measured_frame
        # per-thread pin.Data, never read across calls
        self._scratch: threading.local = (
            threading.local() if same_tree is None else same_tree._scratch
        )
        self.key_frames = tuple(
            dict.fromkeys([measured_frame] + [f for c in closures for f in (c.frame_a, c.frame_b)])
        )
        self.act_q: list[int] = []
        self.act_v: list[int] = []
        self.act_nq: list[int] = []
        for n in actuated:
            j = model.getJointId(n)
            self.act_q.append(model.idx_qs[j])
            self.act_v.append(model.idx_vs[j])
            self.act_nq.append(model.nqs[j])
        act = set(self.act_v)
        self.free_v = np.array([i for i in range(model.nv) if i not in act], dtype=int)
        self.act_v_arr = np.array(self.act_v, dtype=int)
        self.closure_fids = [(self.frame_id(c.frame_a), self.frame_id(c.frame_b)) for c in closures]
        self.n_closure_rows = sum(c.size for c in closures)

    def frame_id(self, name: str) -> int:
        """Pinocchio frame index of a frame (URDF link or joint) by name."""
        return frame_index(self.frame_ids, self.tree, name)

    def joint_id(self, name: str) -> int:
        """Pinocchio id of the joint called ``name`` (UnknownNameError lists the joints)."""
        if not self.model.existJointName(name):
            raise UnknownNameError("joint", name, list(self.model.names)[1:])
        return self.model.getJointId(name)

    def data(self) -> pin.Data:
        """This thread's scratch ``pin.Data``: filled and read within one call only."""
        data = getattr(self._scratch, "data", None)
        if data is None:
            data = self._scratch.data = self.model.createData()
        return data

    def compute(self, q: np.ndarray) -> pin.Data:
        """Placements and joint Jacobians at ``q`` in the scratch data."""
        data = self.data()
        pin.computeJointJacobians(self.model, data, q)
        pin.updateFramePlacements(self.model, data)
        return data

    def residual_of(self, data: pin.Data) -> np.ndarray:
        """(c,) stacked closure residuals [m, rad] at the frames already placed in ``data``."""
        if not self.closures:
            return np.zeros(0)
        oMf = data.oMf
        return np.concatenate(
            [
                c.residual(oMf[a], oMf[b])
                for (a, b), c in zip(self.closure_fids, self.closures, strict=True)
            ]
        )

    def jacobian_of(self, data: pin.Data) -> np.ndarray:
        """(c, nv) Jacobian of the closure residuals at the frames already placed in ``data``."""
        if not self.closures:
            return np.zeros((0, self.model.nv))
        oMf = data.oMf
        model, lwa, local = self.model, pin.LOCAL_WORLD_ALIGNED, pin.LOCAL
        blocks = []
        for (a, b), c in zip(self.closure_fids, self.closures, strict=True):
            if c.is_point:  # world-aligned point velocities directly
                Jb = six_by_nv(pin.getFrameJacobian(model, data, b, lwa))
                Ja = six_by_nv(pin.getFrameJacobian(model, data, a, lwa))
                blocks.append(Jb[:3] - Ja[:3])
            else:
                Ja = six_by_nv(pin.getFrameJacobian(model, data, a, local))
                Jb = six_by_nv(pin.getFrameJacobian(model, data, b, local))
                blocks.append(c.jacobian(oMf[a], oMf[b], Ja, Jb))
        return np.vstack(blocks)

    def snapshot(
        self, q: np.ndarray, data: pin.Data, frames: Sequence[str], jacobian_frames: Sequence[str]
    ) -> Kinematics:
        """A :class:`Kinematics` copy of frame placements and Jacobians at q."""
        model = self.model
        return Kinematics(
            q=np.array(q, dtype=float),
            placements={f: pin.SE3(data.oMf[self.frame_id(f)]) for f in frames},
            jacobians={
                f: six_by_nv(pin.getFrameJacobian(model, data, self.frame_id(f), pin.LOCAL))
                for f in jacobian_frames
            },
            joint_placements=tuple(pin.SE3(M) for M in data.oMi),
            closure_residual=self.residual_of(data),
            closure_jacobian=self.jacobian_of(data),
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
        q = self.check_q(q)
        jac = (self.measured_frame,) if jacobian_frames is None else jacobian_frames
        return self.snapshot(q, self.compute(q), frames or self.key_frames, jac)

    def frame_link(self, frame: str) -> str:
        """URDF link a frame is attached to (a frame named by a joint sits on its child)."""
        self.frame_id(frame)
        if frame in self.tree.joints and frame not in self.tree.links:
            return self.tree.joints[frame].child
        return frame

    @property
    def free_dofs(self) -> np.ndarray:
        """Tangent indices (k,) of the passive (not actuated) degrees of freedom."""
        return self.free_v.copy()

    def frame_placement(self, q: np.ndarray, frame: str | None = None) -> pin.SE3:
        """World placement (a new SE3) of ``frame`` (default: the measured frame) at ``q``."""
        q = self.check_q(q)
        fid = self.frame_id(frame or self.measured_frame)
        return pin.SE3(self.compute(q).oMf[fid])

    def closure_residual(self, q: np.ndarray) -> np.ndarray:
        """Closure residual at configuration q (n_closure_rows,) [m, rad]."""
        return self.residual_of(self.compute(self.check_q(q)))

    def closure_jacobian(self, q: np.ndarray) -> np.ndarray:
        """(n_closure_rows, nv) closure Jacobian at configuration q."""
        return self.jacobian_of(self.compute(self.check_q(q)))

    def check_q(self, q: np.ndarray) -> np.ndarray:
        """The configuration as a float (nq,) array; ShapeError on another shape."""
        q = _as_floats(q, "q")
        if q.shape != (self.model.nq,):
            raise ShapeError(
                f"q must have shape ({self.model.nq},) (nq of {self.name!r}), got {q.shape}"
            )
        return q

    @property
    def n_actuated(self) -> int:
        """Number of actuated joints."""
        return len(self.actuated)

    def actuators_of(self, q: np.ndarray) -> np.ndarray:
        """Actuated joint values (n_act,) of a configuration q (nq,)."""
        return self.actuator_values_batch(self.check_q(q)[None])[0]

    def with_actuators(self, q: np.ndarray, q_act: np.ndarray) -> np.ndarray:
        """Copy of configuration q with the actuated joints set to ``q_act``."""
        return self.actuators_batch(self.check_q(q)[None], self.check_q_act(q_act)[None])[0]

    def actuator_values_batch(self, Q: np.ndarray) -> np.ndarray:
        """Actuated joint values (N, n_act) of configurations ``Q`` (N, nq)."""
        out = np.empty((Q.shape[0], len(self.act_q)))
        for k, (qi, nq) in enumerate(zip(self.act_q, self.act_nq, strict=True)):
            out[:, k] = Q[:, qi] if nq == 1 else np.arctan2(Q[:, qi + 1], Q[:, qi])
        return out

    def actuators_batch(self, Q: np.ndarray, A: np.ndarray) -> np.ndarray:
        """Copies of configurations ``Q`` (N, nq) with the actuators set to ``A`` (N, n_act)."""
        out = np.array(Q, dtype=float)
        for k, (qi, nq) in enumerate(zip(self.act_q, self.act_nq, strict=True)):
            if nq == 1:
                out[:, qi] = A[:, k]
            else:
                out[:, qi], out[:, qi + 1] = np.cos(A[:, k]), np.sin(A[:, k])
        return out

    def check_q_act(self, q_act: np.ndarray) -> np.ndarray:
        """q_act as a float (n_act,) array in the order of ``actuated``; ShapeError otherwise."""
        q_act = _as_floats(q_act, "q_act")
        if q_act.shape != (len(self.actuated),):
            raise ShapeError(
                f"q_act must have shape ({len(self.actuated)},) for actuated joints "
                f"{list(self.actuated)}, got {q_act.shape}"
            )
        return q_act
