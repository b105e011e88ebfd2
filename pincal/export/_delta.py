"""What the delta formats share: three-sphere intersection and the fit over the workspace.

A delta's platform keeps its orientation (each leg's parallelogram), so its controllers
reduce every leg to one *virtual* rod: from a point ``K_i`` that moves with the
actuator (the carriage of a linear delta, the knee of a rotary one, each shifted
inwards by the effector's joint offset) to the controlled point ``p``, of length
``L_i``::

    | p − K_i(q_i) | = L_i,   i = 1, 2, 3                                  (1)

The forward kinematics intersects the three spheres (1) and keeps the solution below
the three centres (the platform hangs under its carriages / knees); the inverse
solves (1) for each ``q_i`` alone. The exported numbers are a least-squares fit of (1)
to the calibrated model's controlled points at workspace readings (the residual of
each sphere, [m]); what (1) with the format's parameters cannot hold shows as the
projection's residual.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares

from pincal.errors import ExportError
from pincal.export._machine import CalibratedMachine

__all__ = ["actuator_signs", "check_delta", "fit", "lowest_intersection", "points"]

Array = NDArray[np.float64]


def check_delta(machine: CalibratedMachine, kind: str, fmt: str) -> None:
    """Refuse a machine that is not a 3-actuator delta with ``kind`` joints.

    Raises:
        ExportError: not three actuators of URDF type ``kind`` (``"prismatic"`` or
            ``"revolute"``), or a measured frame without position.
    """
    mech = machine.calibrated
    types = [mech.tree.joints[j].type for j in mech.actuated]
    if len(types) != 3 or any(t != kind for t in types):
        raise ExportError(
            f"{fmt} describes a delta of three {kind} actuators; {mech.name!r} actuates "
            f"{[f'{j} ({t})' for j, t in zip(mech.actuated, types, strict=True)]} "
            "(use --format generic-table)"
        )
    if not {"x", "y", "z"} <= set(mech.measured_components):
        raise ExportError(f"{fmt} needs the position of the controlled point measured")


def points(machine: CalibratedMachine, q_act: Array) -> Array:
    """(m, 3) controlled points [m] of the calibrated model at readings ``q_act``."""
    return machine.reference(q_act)[:, :3, 3]


def actuator_signs(machine: CalibratedMachine) -> Array:
    """(3,) +1 where raising an actuator's reading raises its moving link, else −1."""
    mech = machine.calibrated
    q0 = mech.q_home
    a0 = mech.actuators_of(q0)
    signs = np.ones(3)
    for k, joint in enumerate(mech.actuated):
        child = mech.tree.joints[joint].child
        step = np.zeros(3)
        step[k] = 1e-4
        up = mech.frame_placement(mech.with_actuators(q0, a0 + step), child).translation[2]
        down = mech.frame_placement(mech.with_actuators(q0, a0 - step), child).translation[2]
        signs[k] = 1.0 if up >= down else -1.0
    return signs


def lowest_intersection(centres: Array, radii: Array) -> Array:
    """The intersection of three spheres below their centres.

    Args:
        centres: (m, 3, 3) sphere centres per pose [m].
        radii: (3,) or (m, 3) sphere radii [m].

    Returns:
        (m, 3) points [m]; NaN where the spheres do not meet.
    """
    c1, c2, c3 = centres[:, 0], centres[:, 1], centres[:, 2]
    r = np.broadcast_to(radii, (len(centres), 3))
    d21 = c2 - c1
    d = np.linalg.norm(d21, axis=1)
    ex = d21 / d[:, None]
    d31 = c3 - c1
    i = np.einsum("mk,mk->m", ex, d31)
    ey = d31 - i[:, None] * ex
    j = np.linalg.norm(ey, axis=1)
    ey /= j[:, None]
    ez = np.cross(ex, ey)
    x = (r[:, 0] ** 2 - r[:, 1] ** 2 + d**2) / (2 * d)
    y = (r[:, 0] ** 2 - r[:, 2] ** 2 + i**2 + j**2) / (2 * j) - i * x / j
    h2 = r[:, 0] ** 2 - x**2 - y**2
    h = np.sqrt(np.where(h2 >= 0, h2, np.nan))
    base = c1 + x[:, None] * ex + y[:, None] * ey
    sign = np.where(ez[:, 2] > 0, -1.0, 1.0)  # towards −z of the world
    return base + (sign * h)[:, None] * ez


def fit(residual: Callable[[Array], Array], start: Array, what: str) -> tuple[Array, float]:
    """Least-squares parameters of sphere residuals (1) and their RMS [m].

    Raises:
        ExportError: the fit does not converge (the machine is not this kind of delta).
    """
    sol = least_squares(residual, start, xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=2000)
    rms = float(np.sqrt(np.mean(sol.fun**2)))
    if not np.all(np.isfinite(sol.x)) or sol.status <= 0:
        raise ExportError(f"{what}: the fit of the delta equations did not converge")
    return sol.x, rms
