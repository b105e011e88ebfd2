"""Loading a mechanism by name or from a file.

Model name or file → :class:`~pincal.model.Mechanism`: the catalogue of
bundled and example-robot-data models, MJCF import, serial chains (re-rooting, base and
tool frames) and DH tables.
"""

from __future__ import annotations

from pincal.model.loading._catalogue import load_mechanism
from pincal.model.loading._dh import (
    DHError,
    DHLayout,
    DHNames,
    DHRow,
    dh_apply_errors,
    dh_fk,
    dh_layout,
)
from pincal.model.loading._dh_model import (
    dh_errors_to_parameters,
    dh_preset,
    dh_urdf,
    parameters_to_dh_errors,
)
from pincal.model.loading._mjcf import load_mjcf, mjcf_to_urdf
from pincal.model.loading._model_files import bundled_models, read_sidecar, resolve_model_path
from pincal.model.loading._named import find_local_sidecar, model_record, resolve_named, srdf_home
from pincal.model.loading._reroot import chain_joints, reroot_urdf
from pincal.model.loading._robots import example_robot_names, example_robot_urdf
from pincal.model.loading._serial import (
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

__all__ = [
    "BASE_JOINT",
    "INSTRUMENT_LINK",
    "TOOL_JOINT",
    "TOOL_LINK",
    "DHError",
    "DHLayout",
    "DHNames",
    "DHRow",
    "bundled_models",
    "chain_joints",
    "chain_preset",
    "dh_apply_errors",
    "dh_errors_to_parameters",
    "dh_fk",
    "dh_layout",
    "dh_preset",
    "dh_urdf",
    "example_robot_names",
    "example_robot_urdf",
    "find_local_sidecar",
    "load_mechanism",
    "load_mjcf",
    "lock_joints",
    "mjcf_to_urdf",
    "model_record",
    "parameters_to_dh_errors",
    "read_sidecar",
    "reroot_urdf",
    "resolve_model_path",
    "resolve_named",
    "serial_mechanism",
    "srdf_home",
    "with_joint_origin",
    "wrap_base_tool",
]
