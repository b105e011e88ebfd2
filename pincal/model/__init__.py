"""Stage 1 — the machine.

URDF tree, typed sidecar, loop closures, :class:`Mechanism`,
parameters (displacements of joint placements), serial chains and DH tables, the
catalogue of bundled models.
"""

from __future__ import annotations

from pincal._limits import Limits, active_limits
from pincal.model._actuator_jacobian import actuator_jacobian, actuator_jacobians
from pincal.model._batch import BatchKinematics, BatchModel
from pincal.model._catalogue import load_mechanism
from pincal.model._closures import (
    COMPONENTS,
    Closure,
    parse_components,
)
from pincal.model._deflection import (
    actual_joint_values,
    deflected_joints,
    deflection_jacobian,
    loaded_terms,
)
from pincal.model._dh import (
    DHError,
    DHLayout,
    DHNames,
    DHRow,
    dh_apply_errors,
    dh_fk,
    dh_layout,
)
from pincal.model._dh_model import (
    dh_errors_to_parameters,
    dh_preset,
    dh_urdf,
    parameters_to_dh_errors,
)
from pincal.model._directions import describe_direction, direction_record, parent_direction
from pincal.model._fixing import fixing_components
from pincal.model._floor import DEFAULT_FLOOR, above_floor
from pincal.model._home_search import conditioning, regular_home
from pincal.model._joint_term_set import (
    actual_shift,
    check_term_data,
    joint_term_bases,
    joint_term_basis,
    joint_term_prior,
    joint_term_shift,
    split_model,
    with_joint_terms,
)
from pincal.model._joint_terms import (
    JointTerm,
    joint_term,
    joint_term_units,
    register_term,
    term_kinds,
)
from pincal.model._kinematics import Kinematics
from pincal.model._linearisation import Linearisation
from pincal.model._mechanism import Mechanism
from pincal.model._mjcf import load_mjcf, mjcf_to_urdf
from pincal.model._model_files import bundled_models, read_sidecar, resolve_model_path
from pincal.model._named import find_local_sidecar, model_record, resolve_named, srdf_home
from pincal.model._newton import SolverOptions
from pincal.model._parameters import (
    DOFS,
    Parameter,
    ParameterSet,
    degenerate_translations,
    full_parameters,
)
from pincal.model._payload import Payload, with_payload
from pincal.model._presets import parameters
from pincal.model._readings import JointReadings
from pincal.model._reroot import chain_joints, reroot_urdf
from pincal.model._robots import example_robot_names, example_robot_urdf
from pincal.model._serial import (
    BASE_JOINT,
    INSTRUMENT_LINK,
    TOOL_JOINT,
    TOOL_LINK,
    chain_preset,
    lock_joints,
    serial_mechanism,
    with_joint_origin,
    wrap_base_tool,
)
from pincal.model._sidecar import (
    JOINT_KINDS,
    WORKSPACE_POSE_KEYS,
    Sidecar,
    Workspace,
    validate_sidecar,
)
from pincal.model._term_strut import strut_loads, struts
from pincal.model._term_temperature import REFERENCE_C as THERMAL_REFERENCE_C
from pincal.model._urdf import (
    MOVABLE_TYPES,
    UrdfJoint,
    UrdfTree,
    se3_from_xyz_rpy,
)
from pincal.model._workspace import (
    sample_actuators,
    sample_pose,
)

__all__ = [
    "BASE_JOINT",
    "COMPONENTS",
    "DEFAULT_FLOOR",
    "DOFS",
    "INSTRUMENT_LINK",
    "JOINT_KINDS",
    "MOVABLE_TYPES",
    "THERMAL_REFERENCE_C",
    "TOOL_JOINT",
    "TOOL_LINK",
    "WORKSPACE_POSE_KEYS",
    "BatchKinematics",
    "BatchModel",
    "Closure",
    "DHError",
    "DHLayout",
    "DHNames",
    "DHRow",
    "JointReadings",
    "JointTerm",
    "Kinematics",
    "Limits",
    "Linearisation",
    "Mechanism",
    "Parameter",
    "ParameterSet",
    "Payload",
    "Sidecar",
    "SolverOptions",
    "UrdfJoint",
    "UrdfTree",
    "Workspace",
    "above_floor",
    "active_limits",
    "actual_joint_values",
    "actual_shift",
    "actuator_jacobian",
    "actuator_jacobians",
    "bundled_models",
    "chain_joints",
    "chain_preset",
    "check_term_data",
    "conditioning",
    "deflected_joints",
    "deflection_jacobian",
    "degenerate_translations",
    "describe_direction",
    "dh_apply_errors",
    "dh_errors_to_parameters",
    "dh_fk",
    "dh_layout",
    "dh_preset",
    "dh_urdf",
    "direction_record",
    "example_robot_names",
    "example_robot_urdf",
    "find_local_sidecar",
    "fixing_components",
    "full_parameters",
    "joint_term",
    "joint_term_bases",
    "joint_term_basis",
    "joint_term_prior",
    "joint_term_shift",
    "joint_term_units",
    "load_mechanism",
    "load_mjcf",
    "loaded_terms",
    "lock_joints",
    "mjcf_to_urdf",
    "model_record",
    "parameters",
    "parameters_to_dh_errors",
    "parent_direction",
    "parse_components",
    "read_sidecar",
    "register_term",
    "regular_home",
    "reroot_urdf",
    "resolve_model_path",
    "resolve_named",
    "sample_actuators",
    "sample_pose",
    "se3_from_xyz_rpy",
    "serial_mechanism",
    "split_model",
    "srdf_home",
    "strut_loads",
    "struts",
    "term_kinds",
    "validate_sidecar",
    "with_joint_origin",
    "with_joint_terms",
    "with_payload",
    "wrap_base_tool",
]
