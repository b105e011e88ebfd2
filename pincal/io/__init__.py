"""Files: measurement, pose and command CSVs, pose-design files, URDF + sidecar export,
atomic writes.
"""

from __future__ import annotations

from pincal.io._atomic import (
    atomic_write_bytes,
    atomic_write_text,
)
from pincal.io._commands_file import (
    read_actuator_rows,
    read_commands,
    write_commands,
)
from pincal.io._instrument_file import (
    read_instrument_data,
    write_instrument_data,
)
from pincal.io._measurement_file import (
    MeasurementFile,
    check_enough_poses,
    read_measurement_file,
    read_measurements,
    write_measurements,
)
from pincal.io._pose_design_file import write_pose_design
from pincal.io._poses_file import (
    read_poses,
    write_poses,
)
from pincal.io._tracker_file import (
    TargetMeasurements,
    write_target_measurements,
)
from pincal.io._units import (
    ANGLE_UNITS,
    LENGTH_UNITS,
)
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
    "read_instrument_data",
    "read_measurement_file",
    "read_measurements",
    "read_poses",
    "save_urdf",
    "write_commands",
    "write_instrument_data",
    "write_measurements",
    "write_pose_design",
    "write_poses",
    "write_target_measurements",
]
