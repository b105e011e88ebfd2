"""Struts lengthened under their own load, solved exactly on the elongated machine.

A strut compliance (:mod:`pincal.model.params._term_strut`) lengthens strut j by
``δL_j = c_j F_j``. The machine that results has its struts lengthened and its actuators
at the command, and the forces that lengthen them are that machine's, at its own closed
configuration: per pose, the fixed point

    δL = c ∘ F(ℓ + δL; u)

on the machine derived from the current geometry with each strut's origin moved by
``δL_j`` along the strut (:meth:`Mechanism.with_joint_origins`), iterated from
``δL = 0`` (a contraction while ``c·∂F/∂L`` stays below 1). The identification's error
model moves joints, so a pose is returned as the actuator values at which the rigid
machine (struts at ℓ) puts the measured frame where the elongated one does, in the
measured components (:meth:`Mechanism.inverse`).

The term's columns (``E·F`` per unit compliance) instead evaluate the forces on that
rigid substitute, carriages moved rather than struts lengthened: their strut directions
differ by ~``E·δL/ℓ``, a force error of 0.4 % at 0.5 mm of sag on the hexaslide, which
the geometric parameters absorbed (docs/nongeometric.md). They remain the Jacobian
(first order in the deflection), and this module the residual.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from pincal.errors import ConvergenceError
from pincal.model.params._strut_statics import link_masses, strut_forces
from pincal.model.params._term_compliance import gravity_model

if TYPE_CHECKING:
    from pincal.model._mechanism import Mechanism

__all__ = ["elongated_joints", "elongation_commands"]

#: most fixed-point iterations of one pose's elongations
MAX_ITERATIONS = 60


def elongated_joints(
    mech: Mechanism, names: tuple[str, ...], c: np.ndarray, u: np.ndarray, tol: float = 1e-13
) -> np.ndarray:
    """Joint values (m, n_act) of the rigid machine that reach the elongated machine's poses.

    Args:
        mech: the machine at the current geometry (its struts at ℓ).
        names: the compliant struts (n).
        c: (n,) their compliances [m/N].
        u: (m, n_act) the actuators' values [rad, m].
        tol: convergence of the elongations [m].

    Raises:
        ConvergenceError: the elongations do not settle (the machine buckles under its
            load), or the rigid machine cannot reach an elongated pose.
    """
    u = np.atleast_2d(np.asarray(u, dtype=float))
    statics = _Statics(mech, names, np.asarray(c, dtype=float))
    out = np.empty_like(u)
    for k, row in enumerate(u):
        dL = np.zeros(len(names))
        q: np.ndarray | None = None
        for _ in range(MAX_ITERATIONS):
            machine = statics.lengthened(dL)
            q = machine.configuration(row, q, pose_index=k)
            dL, step = statics.step(machine, q, dL, k)
            if step <= tol:
                break
        else:
            raise statics.diverged(k, step)
        assert q is not None
        out[k] = mech.inverse(machine.frame_placement(q), q, check_limits=False)
    return out


def elongation_commands(
    mech: Mechanism, names: tuple[str, ...], c: np.ndarray, joints: np.ndarray, tol: float = 1e-13
) -> np.ndarray:
    """The commands (m, n_act) at which the elongated machine reaches the rigid one's poses.

    The inverse of :func:`elongated_joints`: the measured frame's pose of ``mech`` at
    ``joints`` is held, the struts lengthened by the fixed point ``δL = c ∘ F`` of the
    elongated machine at that pose, and its actuators read off.

    Args:
        mech: the machine at the current geometry.
        names: the compliant struts (n).
        c: (n,) their compliances [m/N].
        joints: (m, n_act) joint values of the rigid machine [rad, m].
        tol: convergence of the elongations [m].

    Raises:
        ConvergenceError: the elongations or the inverse kinematics do not settle.
    """
    joints = np.atleast_2d(np.asarray(joints, dtype=float))
    statics = _Statics(mech, names, np.asarray(c, dtype=float))
    out = np.empty_like(joints)
    for k, row in enumerate(joints):
        q = mech.configuration(row, pose_index=k)
        target = mech.frame_placement(q)
        dL = np.zeros(len(names))
        for _ in range(MAX_ITERATIONS):
            machine = statics.lengthened(dL)
            q = machine.inverse_configuration(target, q)
            dL, step = statics.step(machine, q, dL, k)
            if step <= tol:
                break
        else:
            raise statics.diverged(k, step)
        out[k] = machine.actuators_of(q)
    return out


class _Statics:
    """The struts' lengthened machines and their forces (one geometry, one set of c)."""

    def __init__(self, mech: Mechanism, names: tuple[str, ...], c: np.ndarray) -> None:
        self.mech, self.names, self.c = mech, names, c
        self.masses = link_masses(mech)
        self.gravity = gravity_model(mech).gravity
        self.origins = [mech.tree.joints[j].origin for j in names]

    def lengthened(self, dL: np.ndarray) -> Mechanism:
        """The machine with strut j's origin moved by ``dL[j]`` along itself [m]."""
        if not np.any(dL):
            return self.mech
        moved = {}
        for name, o, d in zip(self.names, self.origins, dL, strict=True):
            t = o.translation
            moved[name] = pin.SE3(o.rotation, t + d * t / np.linalg.norm(t))
        return self.mech.with_joint_origins(moved)

    def step(
        self, machine: Mechanism, q: np.ndarray, dL: np.ndarray, k: int
    ) -> tuple[np.ndarray, float]:
        """(new elongations ``c ∘ F`` at ``q`` of ``machine`` [m], largest change [m])."""
        model = pin.Model(machine.model)
        model.gravity = self.gravity
        new = self.c * strut_forces(machine, model, q, self.names, self.masses, k)[0]
        return new, float(np.max(np.abs(new - dL)))

    def diverged(self, k: int, step: float) -> ConvergenceError:
        return ConvergenceError(
            f"{self.mech.name!r} at pose {k}: the struts' elongation under load does not "
            f"settle after {MAX_ITERATIONS} iterations (last change {step:.3g} m): the "
            f"compliances {np.array2string(self.c, precision=3)} m/N let the machine buckle "
            f"under its load; start from smaller compliances or check the payload and masses",
            residual=step,
        )
