"""Errors of measurement data: file layout, columns, cells, units, frames, noise, fits."""

from __future__ import annotations

from collections.abc import Sequence

from pincal.errors._base import PincalError
from pincal.errors._inputs import InputFileError

__all__ = [
    "ActuatorRangeError",
    "BadValueError",
    "ColumnError",
    "ConditionError",
    "DuplicateDataError",
    "FrameMismatchError",
    "ImportMatchError",
    "MeasurementError",
    "MeasurementFileError",
    "MeasurementFormatError",
    "MovedTargetError",
    "NoiseEstimationError",
    "NonFiniteValueError",
    "OrientationValueError",
    "PoseFitError",
    "ShiftedHeaderError",
    "UnitMismatchError",
]


class MeasurementError(PincalError):
    """Measurement data are malformed (missing columns, NaN, wrong units, ...)."""


class NoiseEstimationError(MeasurementError):
    """The measurement noise is not declared and cannot be estimated from the residuals."""


class ConditionError(MeasurementError):
    """A per-pose condition a term needs (the temperature) is missing, constant or bad."""


class MeasurementFormatError(MeasurementError):
    """The file's header or layout is malformed (line named in the message)."""


class MeasurementFileError(MeasurementFormatError, InputFileError):
    """A data file (measurements, poses, commands…) is missing, unreadable or not text."""


class UnitMismatchError(MeasurementError):
    """The values' size says their declared unit is wrong (millimetres read as metres)."""


class DuplicateDataError(MeasurementError):
    """The same measurements are given twice (one file twice, or a byte copy)."""


class ShiftedHeaderError(MeasurementFormatError):
    """A table's title line does not sit above its columns (more or fewer cells per row)."""


class FrameMismatchError(MeasurementError):
    """The file measures another frame than the model's measured frame."""


class ColumnError(MeasurementError):
    """Columns are missing or not understood.

    Attributes:
        missing: column names the model needs but the file lacks.
        unknown: column names the file has but nobody asked for.
    """

    def __init__(self, message: str, missing: Sequence[str] = (), unknown: Sequence[str] = ()):
        self.missing = list(missing)
        self.unknown = list(unknown)
        super().__init__(message)


class BadValueError(MeasurementError):
    """A cell is not a number. Attributes: row (1-based data row), column."""

    def __init__(self, message: str, row: int, column: str):
        self.row, self.column = row, column
        super().__init__(message)


class NonFiniteValueError(BadValueError):
    """A cell is NaN or infinite."""


class OrientationValueError(BadValueError):
    """An orientation cell is not of its declared convention (quaternion norm, angle range)."""


class ActuatorRangeError(BadValueError):
    """An actuator value lies far outside its joint's URDF limits.

    Attributes: row, column (as :class:`BadValueError`), joint, limits (lower, upper)
    [m or rad].
    """

    def __init__(
        self, message: str, row: int, column: str, joint: str, limits: tuple[float, float]
    ):
        self.joint, self.limits = joint, limits
        super().__init__(message, row, column)


class PoseFitError(MeasurementError):
    """The targets of one pose cannot be fitted (moved target, collinear). Attribute: row."""

    def __init__(self, message: str, row: int):
        self.row = row
        super().__init__(message)


class MovedTargetError(MeasurementError):
    """A target's fit residual exceeds the allowed maximum (the SMR or its nest moved).

    Attributes:
        target_index: index of the worst target (row of the point arrays).
        residual: its residual distance [m].
        max_residual: the allowed maximum [m].
    """

    def __init__(self, target_index: int, residual: float, max_residual: float):
        self.target_index = target_index
        self.residual = residual
        self.max_residual = max_residual
        super().__init__(
            f"target {target_index} does not fit the rigid body: residual "
            f"{residual * 1e3:.4f} mm > allowed {max_residual * 1e3:.4f} mm "
            f"(has the target or its nest moved?)"
        )


class ImportMatchError(MeasurementError):
    """Imported tracker points and controller-log rows do not pair up.

    Attributes:
        points_lines: 1-based lines of the points file left without a log row.
        log_lines: 1-based lines of the controller log left without points.
    """

    def __init__(
        self, message: str, points_lines: Sequence[int] = (), log_lines: Sequence[int] = ()
    ):
        self.points_lines = list(points_lines)
        self.log_lines = list(log_lines)
        super().__init__(message)
