"""Model files read into descriptions.

Files → descriptions: the URDF tree and its checks, the typed sidecar
(closures, readings, workspace), the MJCF element tree, the Pinocchio model built from
them and the measured frame's defaults. Nothing here solves kinematics.
"""

from __future__ import annotations

from pincal.model.files._build import build_model, lock_joints
from pincal.model.files._closures import (
    COMPONENTS,
    Closure,
    measured_jacobian,
    measurement_residual,
    parse_components,
)
from pincal.model.files._frames import default_measured_frame, measured_frame_candidates
from pincal.model.files._mjcf_tree import MjcfTree, euler_xyz, quat_matrix, unit, vec
from pincal.model.files._readings import JointReadings
from pincal.model.files._sidecar import (
    JOINT_KINDS,
    WORKSPACE_POSE_KEYS,
    Sidecar,
    Workspace,
    validate_sidecar,
)
from pincal.model.files._urdf import MOVABLE_TYPES, UrdfJoint, UrdfTree, se3_from_xyz_rpy
from pincal.model.files._urdf_check import captured_stderr

__all__ = [
    "COMPONENTS",
    "JOINT_KINDS",
    "MOVABLE_TYPES",
    "WORKSPACE_POSE_KEYS",
    "Closure",
    "JointReadings",
    "MjcfTree",
    "Sidecar",
    "UrdfJoint",
    "UrdfTree",
    "Workspace",
    "build_model",
    "captured_stderr",
    "default_measured_frame",
    "euler_xyz",
    "lock_joints",
    "measured_frame_candidates",
    "measured_jacobian",
    "measurement_residual",
    "parse_components",
    "quat_matrix",
    "se3_from_xyz_rpy",
    "unit",
    "validate_sidecar",
    "vec",
]
