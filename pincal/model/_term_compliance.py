"""Joint compliance under the arm's own weight: ``δq_i = c_i · τ_i(q)``.

``τ`` is Pinocchio's generalised gravity (:func:`pinocchio.computeGeneralizedGravity`)
of the nominal model's link inertias at the commanded configuration [N·m, N]; ``c_i``
is the joint's compliance [rad/(N·m)] (revolute) or [m/N] (prismatic). Serial chains
only: the static load of a closed loop needs its constraint forces (not done).
Gravity is ``−9.81 m/s²`` along the z axis of the robot's own base: the model's world
frame, or — for a robot wrapped with an instrument frame (``base_frame`` joint, e.g. a
marker calibration whose world is the capture system) — the frame below that joint.
A joint whose gravity torque never changes (a vertical first axis) gets a zero basis,
which the rank analysis reports as unidentifiable.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, ClassVar

import numpy as np
import pinocchio as pin

from pincal.errors import ParameterError
from pincal.model._joint_terms import JointTerm, register_term
from pincal.model._serial import BASE_JOINT

if TYPE_CHECKING:
    from pincal.model._mechanism import Mechanism

__all__ = ["Compliance"]


class Compliance(JointTerm):
    """Joint compliance under gravity (1σ prior 1e-5 rad/(N·m): 0.5 mrad at 50 N·m)."""

    kind: ClassVar[str] = "compliance"
    dofs: ClassVar[tuple[str, ...]] = ("compliance",)
    prior: ClassVar[float] = 1e-5

    def unit(self, joint_type: str) -> str:
        return "m/N" if joint_type == "prismatic" else "rad/(N·m)"

    def check(self, mech: Mechanism, joint: str) -> None:
        super().check(mech, joint)
        if mech.closures:
            raise ParameterError(
                f"compliance terms need a serial chain; {mech.name!r} has closed loops "
                f"(strut compliance from constraint forces is not implemented)"
            )
        if sum(i.mass for i in mech.model.inertias) <= 0:
            raise ParameterError(
                f"model {mech.name!r} has no link masses: a compliance under gravity needs "
                f"<inertial> elements in the URDF"
            )

    def basis(self, mech: Mechanism, q_act: np.ndarray) -> np.ndarray:
        q_act = np.atleast_2d(np.asarray(q_act, dtype=float))
        model = pin.Model(mech.model)  # a copy: its gravity is set below
        model.gravity = pin.Motion(np.concatenate([_gravity(mech), np.zeros(3)]))
        data = model.createData()
        cols = [model.idx_vs[model.getJointId(a)] for a in mech.actuated]
        out = np.empty((q_act.shape[0], len(cols), 1))
        for k, row in enumerate(q_act):
            q = mech.with_actuators(mech.q_home, row)
            out[k, :, 0] = pin.computeGeneralizedGravity(model, data, q)[cols]
        return out


def _gravity(mech: Mechanism) -> np.ndarray:
    """(3,) gravity in the model's world frame [m/s²]: −9.81 along the robot base's z."""
    g = np.array([0.0, 0.0, -9.81])
    if BASE_JOINT not in mech.tree.joints or not mech.model.existFrame(BASE_JOINT):
        return g
    data = mech.model.createData()
    pin.framesForwardKinematics(mech.model, data, mech.q_home)
    return data.oMf[mech.model.getFrameId(BASE_JOINT)].rotation @ g


register_term(Compliance())
