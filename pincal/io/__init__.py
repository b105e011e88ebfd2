"""Files: measurement, pose and command CSVs, pose-design files, URDF + sidecar export,
atomic writes.
"""

from __future__ import annotations

from pincal.io._atomic import (
    atomic_write_bytes,
    atomic_write_text,
)
from pincal.io._datafiles import (
    ANGLE_UNITS,
    LENGTH_UNITS,
    MeasurementFile,
    TargetMeasurements,
    check_enough_poses,
    read_actuator_rows,
    read_commands,
    read_measurement_file,
    read_measurements,
    read_poses,
    write_commands,
    write_measurements,
    write_poses,
    write_target_measurements,
)
from pincal.io._pose_design_file import write_pose_design
from pincal.io._urdf_export import (
    save_urdf,
)

__all__ = [
    "ANGLE_UNITS",
    "LENGTH_UNITS",
    "MeasurementFile",
    "TargetMeasurements",
    "atomic_write_bytes",
    "atomic_write_text",
    "check_enough_poses",
    "read_actuator_rows",
    "read_commands",
    "read_measurement_file",
    "read_measurements",
    "read_poses",
    "save_urdf",
    "write_commands",
    "write_measurements",
    "write_pose_design",
    "write_poses",
    "write_target_measurements",
]
