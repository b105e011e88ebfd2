"""Instrument registration: the measuring instrument's frame solved in closed form first.

When the instrument frame is far from the robot's base frame (metres, tens of degrees),
a linearised identification started at the identity would converge slowly or not at
all. :func:`register_instrument` solves it first: the nominal model's predicted
measured-frame positions (in the robot base frame) are fitted onto the measured
positions by a best-fit rigid transform (:func:`fit_rigid_transform`), and that
transform becomes the ``base_frame`` origin of the returned mechanism. Identification
then refines it with the six ``base_frame`` parameters (small corrections, together
with the robot's own errors, which bias the closed-form fit slightly).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pincal.errors import MeasurementError, ModelFileError, UnknownNameError
from pincal.measure._measurements import Measurements
from pincal.measure._tracker import RigidFit, fit_rigid_transform
from pincal.model import BASE_JOINT, Mechanism, with_joint_origin

__all__ = ["Registration", "register_instrument"]


@dataclass(frozen=True)
class Registration:
    """Instrument-frame registration by a best-fit rigid transform.

    Attributes:
        T_instrument_base: the fitted ``base_frame`` origin (robot base in the
            instrument frame).
        fit: the rigid fit of the nominal model's predicted positions (base frame)
            onto the measured positions (instrument frame); ``fit.rms`` [m] is the
            residual left for identification (the robot's own errors and noise).
        mechanism: the input mechanism with ``base_frame`` set to ``T_instrument_base``.
    """

    T_instrument_base: pin.SE3
    fit: RigidFit
    mechanism: Mechanism


def register_instrument(
    mech: Mechanism, measurements: Measurements, base_joint: str = BASE_JOINT
) -> Registration:
    """Solve the instrument frame first: fit the nominal predictions onto the measurements.

    Args:
        mech: mechanism with a base-frame fixed joint ``base_joint`` directly below the
            root (see :func:`wrap_base_tool`).
        measurements: at least 3 poses with non-collinear measured positions.
        base_joint: name of the fixed joint between the root link and the mechanism
            whose origin is re-fitted (default ``"base_frame"``).

    Raises:
        UnknownNameError: no ``base_joint``.
        MeasurementError: too few or collinear points.
    """
    if base_joint not in mech.tree.joints:
        raise UnknownNameError("joint", base_joint, list(mech.tree.joints))
    if mech.tree.joints[base_joint].parent != mech.tree.root_link:
        raise ModelFileError(f"joint {base_joint!r} must hang from the root link")
    if len(measurements) < 3:
        raise MeasurementError(f"registration needs at least 3 poses, got {len(measurements)}")
    T_current = mech.tree.joints[base_joint].origin
    qs = mech.configurations(measurements.q_act)
    predicted_world = np.empty((len(qs), 3))
    for i, q in enumerate(qs):
        predicted_world[i] = mech.frame_placement(q).translation
    predicted_base = (predicted_world - T_current.translation) @ T_current.rotation
    fit = fit_rigid_transform(predicted_base, measurements.positions)
    return Registration(fit.T, fit, with_joint_origin(mech, base_joint, fit.T))
