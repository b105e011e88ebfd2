"""Compatibility alias: the file formats now live in one module per file kind.

:mod:`pincal.io._csv` (CSV core), :mod:`pincal.io._units`,
:mod:`pincal.io._measurement_file`, :mod:`pincal.io._tracker_file`,
:mod:`pincal.io._poses_file` and :mod:`pincal.io._commands_file`. Import the public
names from :mod:`pincal.io`; this alias remains only for callers not yet moved
(pincal.design._selection) and holds no code.
"""

from __future__ import annotations

from pincal.io._commands_file import read_actuator_rows, read_commands, write_commands
from pincal.io._measurement_file import (
    MeasurementFile,
    check_enough_poses,
    read_measurement_file,
    read_measurements,
    write_measurements,
)
from pincal.io._poses_file import read_poses, write_poses
from pincal.io._tracker_file import TargetMeasurements, write_target_measurements
from pincal.io._units import ANGLE_UNITS, LENGTH_UNITS

__all__ = [
    "ANGLE_UNITS",
    "LENGTH_UNITS",
    "MeasurementFile",
    "TargetMeasurements",
    "check_enough_poses",
    "read_actuator_rows",
    "read_commands",
    "read_measurement_file",
    "read_measurements",
    "read_poses",
    "write_commands",
    "write_measurements",
    "write_poses",
    "write_target_measurements",
]
