"""Kinematic queries of a mechanism at a given configuration (no shared state).

:class:`KinematicQueries` is the part of :class:`~pincal.model.Mechanism` that
evaluates placements, Jacobians and closure residuals at a configuration ``q``; each
call fills a per-thread scratch ``pin.Data`` and returns fresh arrays.
"""

from __future__ import annotations

import threading
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pincal.errors import ShapeError, UnknownNameError
from pincal.model._closures import Closure
from pincal.model._newton import SolverOptions
from pincal.model._sidecar import Sidecar
from pincal.model._urdf import UrdfTree

__all__ = ["KinematicQueries", "Kinematics"]


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


class KinematicQueries:
    """Configuration-in, fresh-arrays-out queries (mixed into Mechanism).

    Expects the attributes set by ``Mechanism.__init__`` (declared here for the mixins).
    """

    model: pin.Model
    tree: UrdfTree
    sidecar: Sidecar
    name: str
    options: SolverOptions
    closures: tuple[Closure, ...]
    actuated: tuple[str, ...]
    measured_frame: str
    key_frames: tuple[str, ...]
    q_home: np.ndarray
    n_closure_rows: int
    _scratch: threading.local
    _frame_ids: dict[str, int]
    _closure_fids: list[tuple[int, int]]
    _act_q: list[int]
    _act_v: list[int]
    _act_nq: list[int]
    _act_v_arr: np.ndarray
    _free_v: np.ndarray
    _assembly_notes: list[str]

    def frame_id(self, name: str) -> int:
        """Pinocchio frame index of a frame (URDF link or joint) by name."""
        if name not in self._frame_ids:
            raise UnknownNameError("frame", name, self.tree.links)
        return self._frame_ids[name]

    def joint_id(self, name: str) -> int:
        if not self.model.existJointName(name):
            raise UnknownNameError("joint", name, list(self.model.names)[1:])
        return self.model.getJointId(name)

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
        return self._actuator_values_batch(self._check_q(q)[None])[0]

    def with_actuators(self, q: np.ndarray, q_act: np.ndarray) -> np.ndarray:
        """Copy of configuration q with the actuated joints set to ``q_act``."""
        return self._actuators_batch(self._check_q(q)[None], self._check_q_act(q_act)[None])[0]

    def _actuator_values_batch(self, Q: np.ndarray) -> np.ndarray:
        """Actuated joint values (N, n_act) of configurations ``Q`` (N, nq)."""
        out = np.empty((Q.shape[0], len(self._act_q)))
        for k, (qi, nq) in enumerate(zip(self._act_q, self._act_nq, strict=True)):
            out[:, k] = Q[:, qi] if nq == 1 else np.arctan2(Q[:, qi + 1], Q[:, qi])
        return out

    def _actuators_batch(self, Q: np.ndarray, A: np.ndarray) -> np.ndarray:
        """Copies of configurations ``Q`` (N, nq) with the actuators set to ``A`` (N, n_act)."""
        out = np.array(Q, dtype=float)
        for k, (qi, nq) in enumerate(zip(self._act_q, self._act_nq, strict=True)):
            if nq == 1:
                out[:, qi] = A[:, k]
            else:
                out[:, qi], out[:, qi + 1] = np.cos(A[:, k]), np.sin(A[:, k])
        return out

    def _check_q_act(self, q_act: np.ndarray) -> np.ndarray:
        q_act = _as_floats(q_act, "q_act")
        if q_act.shape != (len(self.actuated),):
            raise ShapeError(
                f"q_act must have shape ({len(self.actuated)},) for actuated joints "
                f"{list(self.actuated)}, got {q_act.shape}"
            )
        return q_act
