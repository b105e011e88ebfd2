"""Compliance under static load: ``δq_i = c_i · τ_i(q)`` on every actuated joint.

``τ`` is the generalised force the actuators hold at static equilibrium under gravity
[N·m, N], from the nominal model's link inertias (a payload is a link with an
``<inertial>`` fixed to the tool, :func:`pincal.model.with_payload`):

* serial chain: Pinocchio's generalised gravity (:func:`pinocchio.computeGeneralizedGravity`)
  of the actuated joints;
* closed loops (a Stewart platform's legs, a parallel arm's motors): the equilibrium
  ``g(q) = Sᵀ τ + J_cᵀ λ`` of the closed configuration solved for the actuator forces
  ``τ`` and the loop-closure constraint forces ``λ`` (``S`` selects the actuated
  tangent dofs, ``J_c`` the closure Jacobian). On a UPS leg ``τ`` is the leg's axial
  force and ``c`` its axial compliance [m/N]. A fixed-length strut (a hexaslide's) is
  not an actuated joint: its compliance is :mod:`pincal.model.params._term_strut`.

``c_i`` is the joint's compliance [rad/(N·m)] (revolute) or [m/N] (prismatic). With
this sign convention a joint that yields to the load it holds (a spring of stiffness
``k``) has ``c = −1/k``. Gravity is ``−9.81 m/s²`` along the z axis of the robot's own
base: the model's world frame, or — for a robot wrapped with an instrument frame
(``base_frame`` joint, e.g. a marker calibration whose world is the capture system) —
the frame below that joint. A joint whose load never changes (a vertical first axis)
gets a constant or zero basis, which the rank analysis reports as unidentifiable.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, ClassVar

import numpy as np
import pinocchio as pin

from pincal.errors import ParameterError
from pincal.model.loading import BASE_JOINT
from pincal.model.params._joint_terms import JointTerm, register_term

if TYPE_CHECKING:
    from pincal.model._mechanism import Mechanism

__all__ = ["Compliance", "actuator_load"]

#: relative residual of the equilibrium above which the actuators do not hold the load
_EQUILIBRIUM_TOL = 1e-6


class Compliance(JointTerm):
    """Compliance under static load (1σ prior 1e-5 rad/(N·m) or m/N: 0.5 mrad at 50 N·m)."""

    kind: ClassVar[str] = "compliance"
    dofs: ClassVar[tuple[str, ...]] = ("compliance",)
    loaded: ClassVar[bool] = True
    prior: ClassVar[float] = 1e-5

    def unit(self, joint_type: str) -> str:
        return "m/N" if joint_type == "prismatic" else "rad/(N·m)"

    def check(self, mech: Mechanism, joint: str) -> None:
        super().check(mech, joint)
        if sum(i.mass for i in mech.model.inertias) <= 0:
            raise ParameterError(
                f"model {mech.name!r} has no link masses: a compliance under gravity needs "
                f"<inertial> elements in the URDF (or a payload: pincal.model.with_payload)"
            )
        if mech.closures:
            held_once(mech)

    def basis(self, mech: Mechanism, q_act: np.ndarray) -> np.ndarray:
        return actuator_load(mech, q_act)[:, :, None]


def actuator_load(mech: Mechanism, q_act: np.ndarray) -> np.ndarray:
    """Generalised forces (m, n_act) the actuators hold under gravity [N·m, N].

    Args:
        mech: the mechanism (its link inertias, payload included).
        q_act: (m, n_act) actuator values [rad, m]; closed loops are assembled on
            home's branch (:meth:`Mechanism.configurations`).

    Raises:
        ParameterError: a closed-loop pose the actuators and closures do not hold in
            equilibrium (a passive joint free to fall), or whose actuator forces are
            not unique (redundant actuation).
    """
    q_act = np.atleast_2d(np.asarray(q_act, dtype=float))
    model = gravity_model(mech)
    data = model.createData()
    cols = [model.idx_vs[model.getJointId(a)] for a in mech.actuated]
    out = np.empty((q_act.shape[0], len(cols)))
    if not mech.closures:
        for k, row in enumerate(q_act):
            q = mech.with_actuators(mech.q_home, row)
            out[k] = pin.computeGeneralizedGravity(model, data, q)[cols]
        return out
    S = np.zeros((model.nv, len(cols)))
    S[cols, np.arange(len(cols))] = 1.0
    for k, q in enumerate(mech.configurations(q_act)):
        out[k] = equilibrium(mech, model, data, S, q, k)[: len(cols)]
    return out


def equilibrium(
    mech: Mechanism, model: pin.Model, data: pin.Data, S: np.ndarray, q: np.ndarray, k: int
) -> np.ndarray:
    """``[τ; λ]`` solving ``g(q) = S τ + J_cᵀ λ`` at a closed configuration.

    τ (n_act,) the actuator forces [N·m, N], λ (n_closure_rows,) the loop-closure
    constraint forces, in the rows of :meth:`Mechanism.closure_jacobian`.
    """
    g = pin.computeGeneralizedGravity(model, data, q)
    A = np.hstack([S, mech.closure_jacobian(q).T])
    x, *_ = np.linalg.lstsq(A, g, rcond=None)
    miss = float(np.linalg.norm(A @ x - g))
    if miss > _EQUILIBRIUM_TOL * max(float(np.linalg.norm(g)), 1.0):
        raise ParameterError(
            f"{mech.name!r} at pose {k}: the actuators and closures do not hold the load "
            f"(equilibrium residual {miss:.3g} N·m); a passive joint is free to move under "
            f"gravity, so a compliance under load is not defined"
        )
    return x


def held_once(mech: Mechanism) -> None:
    """Refuse a closed loop whose actuator forces are not unique or not in equilibrium."""
    model = gravity_model(mech)
    cols = [model.idx_vs[model.getJointId(a)] for a in mech.actuated]
    S = np.zeros((model.nv, len(cols)))
    S[cols, np.arange(len(cols))] = 1.0
    A = np.hstack([S, mech.closure_jacobian(mech.q_home).T])
    _, sv, Vt = np.linalg.svd(A)
    rank = int(np.sum(sv > 1e-9 * sv[0]))
    if np.linalg.norm(Vt[rank:, : len(cols)]) > 1e-6:
        raise ParameterError(
            f"{mech.name!r}: its actuator forces under load are not unique (redundant "
            f"actuation), so a compliance per actuator is not defined"
        )
    equilibrium(mech, model, model.createData(), S, mech.q_home, 0)


def gravity_model(mech: Mechanism) -> pin.Model:
    """A copy of the mechanism's model with gravity along its robot base's −z."""
    model = pin.Model(mech.model)
    model.gravity = pin.Motion(np.concatenate([gravity_wrench(mech), np.zeros(3)]))
    return model


def gravity_wrench(mech: Mechanism) -> np.ndarray:
    """(3,) gravity in the model's world frame [m/s²]: −9.81 along the robot base's z."""
    g = np.array([0.0, 0.0, -9.81])
    if BASE_JOINT not in mech.tree.joints or not mech.model.existFrame(BASE_JOINT):
        return g
    data = mech.model.createData()
    pin.framesForwardKinematics(mech.model, data, mech.q_home)
    return data.oMf[mech.model.getFrameId(BASE_JOINT)].rotation @ g


register_term(Compliance())
