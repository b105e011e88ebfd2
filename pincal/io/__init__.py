"""Files: every format pincal reads and writes.

The calibration directory, measurement, pose and command CSVs, pose-design
files, URDF + sidecar export, atomic writes.
"""

from __future__ import annotations

from pincal.io._atomic import (
    atomic_write_bytes,
    atomic_write_text,
    calibration_lock,
    output_target,
)
from pincal.io._calibration_dir import (
    CALIBRATION_VERSION,
    CalibrationDirectory,
    read_calibration,
)
from pincal.io._calibration_replace import check_replaceable
from pincal.io._calibration_write import write_calibration
from pincal.io._commands_file import (
    read_actuator_rows,
    read_commands,
    write_commands,
)
from pincal.io._csv import file_kind
from pincal.io._delimited import parse_mapping
from pincal.io._digest import sha256_file
from pincal.io._file_names import (
    CALIBRATED_SIDECAR,
    CALIBRATED_URDF,
    CALIBRATION_FORMAT,
    IDENTIFICATION_FILE,
    MANIFEST,
    MODEL_RECORD,
    VALIDATION_FILE,
)
from pincal.io._fleet_file import Fleet, FleetUnit, fleet_text, read_fleet
from pincal.io._gcode import GcodeMove, GcodeProgram, read_gcode, write_gcode
from pincal.io._identification_file import read_identification
from pincal.io._import_tracker import (
    TrackerImport,
    TrackerImportOptions,
    import_tracker,
)
from pincal.io._instrument_file import (
    read_instrument_data,
    write_instrument_data,
)
from pincal.io._instrument_registry import (
    INSTRUMENT_FILES,
    is_instrument_file,
    read_instrument_file,
)
from pincal.io._joint_columns import joint_columns, read_joints
from pincal.io._marker_file import (
    MarkerData,
    distinct_markers,
    read_marker_data,
    read_marker_sets,
    read_marker_table,
)
from pincal.io._measurement_file import (
    MeasurementFile,
    check_enough_poses,
    read_measurement_file,
    read_measurements,
    write_measurements,
)
from pincal.io._pose_design_file import write_pose_design
from pincal.io._pose_rows import read_pose_rows
from pincal.io._poses_file import (
    PoseFile,
    read_pose_file,
    read_poses,
    write_poses,
)
from pincal.io._result_store import ResultStore
from pincal.io._socket_file import read_socket_data, write_socket_data
from pincal.io._socket_table import SocketTable, read_socket_table, socket_id
from pincal.io._tracker_file import (
    TargetMeasurements,
    write_target_measurements,
)
from pincal.io._units import (
    ANGLE_UNITS,
    LENGTH_UNITS,
    si_actuator_units,
)
from pincal.io._urdf_export import (
    save_urdf,
)

__all__ = [
    "ANGLE_UNITS",
    "CALIBRATED_SIDECAR",
    "CALIBRATED_URDF",
    "CALIBRATION_FORMAT",
    "CALIBRATION_VERSION",
    "IDENTIFICATION_FILE",
    "INSTRUMENT_FILES",
    "LENGTH_UNITS",
    "MANIFEST",
    "MODEL_RECORD",
    "VALIDATION_FILE",
    "CalibrationDirectory",
    "Fleet",
    "FleetUnit",
    "GcodeMove",
    "GcodeProgram",
    "MarkerData",
    "MeasurementFile",
    "PoseFile",
    "ResultStore",
    "SocketTable",
    "TargetMeasurements",
    "TrackerImport",
    "TrackerImportOptions",
    "atomic_write_bytes",
    "atomic_write_text",
    "calibration_lock",
    "check_enough_poses",
    "check_replaceable",
    "distinct_markers",
    "file_kind",
    "fleet_text",
    "import_tracker",
    "is_instrument_file",
    "joint_columns",
    "output_target",
    "parse_mapping",
    "read_actuator_rows",
    "read_calibration",
    "read_commands",
    "read_fleet",
    "read_gcode",
    "read_identification",
    "read_instrument_data",
    "read_instrument_file",
    "read_joints",
    "read_marker_data",
    "read_marker_sets",
    "read_marker_table",
    "read_measurement_file",
    "read_measurements",
    "read_pose_file",
    "read_pose_rows",
    "read_poses",
    "read_socket_data",
    "read_socket_table",
    "save_urdf",
    "sha256_file",
    "si_actuator_units",
    "socket_id",
    "write_calibration",
    "write_commands",
    "write_gcode",
    "write_instrument_data",
    "write_measurements",
    "write_pose_design",
    "write_poses",
    "write_socket_data",
    "write_target_measurements",
]
