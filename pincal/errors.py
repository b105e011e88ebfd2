"""Exception hierarchy of pincal.

Every error a user can cause derives from :class:`PincalError`. Messages say what
was wrong and what would be valid (names, shapes, units), so the CLI can print
them as one line without a traceback. Exceptions carry the offending data as
attributes for programmatic use.
"""

from __future__ import annotations

import reprlib
from collections.abc import Iterable, Sequence

__all__ = [
    "ActuatorRangeError",
    "BadValueError",
    "CalibrationDirectoryError",
    "CampaignError",
    "ClosureError",
    "ColumnError",
    "ConditionError",
    "ConvergenceError",
    "DuplicateDataError",
    "ExportError",
    "FleetFileError",
    "FrameMismatchError",
    "ImmutableError",
    "ImportMatchError",
    "InputFileError",
    "InputLimitError",
    "ItemFailedError",
    "MeasurementError",
    "MeasurementFileError",
    "MeasurementFormatError",
    "MissingExtraError",
    "MobilityError",
    "ModelFileError",
    "MovedTargetError",
    "NoTestCubeError",
    "NoiseEstimationError",
    "NonFiniteValueError",
    "OptionValueError",
    "OrientationValueError",
    "OutputPathError",
    "ParameterError",
    "PincalError",
    "PoseFitError",
    "QualityGateError",
    "ReportError",
    "ShapeError",
    "ShiftedHeaderError",
    "SingularConfigurationError",
    "SolverOptionError",
    "TooFewPosesError",
    "UnidentifiableError",
    "UnitMismatchError",
    "UnknownNameError",
    "UnreachablePoseError",
    "VisualizationError",
    "clip",
]


class PincalError(Exception):
    """Root of all pincal errors."""


def clip(value: object, limit: int = 80, *, quote: bool = False) -> str:
    """Return bounded text of a user value for a message, at most ``limit`` characters.

    Every user-supplied value that goes into a message passes through here, so a
    huge or hostile value (a YAML alias bomb, a 10 MB CSV cell, a 5 000-digit integer)
    cannot make the message itself huge or slow. Strings are shown as they are, with
    control characters escaped (quoted with ``quote=True``); other values by a ``repr``
    bounded in depth and item count (:mod:`reprlib`).

    Args:
        value: anything.
        limit: maximum length of the returned text, in characters.
        quote: put strings in single quotes (as ``repr`` would).

    Returns:
        The text, ending in "… (N chars)" when cut.
    """
    if isinstance(value, str):
        text = value.encode("unicode_escape", "backslashreplace").decode("ascii", "replace")
        if quote:
            text = "'" + text.replace("'", "\\'") + "'"
    elif isinstance(value, int) and not isinstance(value, bool) and value.bit_length() > 128:
        text = f"<integer of ~{int(value.bit_length() * 0.30103) + 1} digits>"
    elif isinstance(value, (list, tuple, set, dict)) and len(value) > limit:
        text = f"<{type(value).__name__} of {len(value)} items>"
    else:
        short = reprlib.Repr()
        short.maxlevel, short.maxstring, short.maxother = 3, limit, limit
        try:
            text = short.repr(value)
        except ValueError:  # an integer too long to print, nested somewhere
            text = f"<{type(value).__name__}>"
    if len(text) <= limit:
        return text
    tail = f"… ({len(text)} chars)"
    return text[: max(limit - len(tail), 1)] + tail


class InputLimitError(PincalError):
    """An input is larger than a stated limit (file size, model size, option value)."""


def _listing(names: Iterable[str], limit: int = 40) -> str:
    names = list(names)
    shown = ", ".join(repr(n) for n in names[:limit])
    if len(names) > limit:
        shown += f", … ({len(names) - limit} more)"
    return shown


class InputFileError(PincalError):
    """An input file is missing, not a regular file, unreadable or not UTF-8 text."""


class ModelFileError(InputFileError):
    """A URDF or sidecar file is missing, malformed or inconsistent."""


class ShapeError(PincalError, ValueError):
    """An array argument has the wrong shape (or is not numeric).

    Also a ValueError, so callers that caught the plain ValueError keep working.
    """


class UnknownNameError(PincalError, KeyError):
    """A frame, joint, parameter or preset name does not exist.

    Attributes:
        kind: what was looked up ("frame", "joint", "preset", ...).
        name: the name that was not found.
        valid: the names that would have been accepted.
    """

    def __init__(self, kind: str, name: str, valid: Iterable[str], hint: str = ""):
        self.kind = kind
        self.name = name
        self.valid = list(valid)
        super().__init__(
            f"{kind} {clip(name, quote=True)} not found; {kind}s are: {_listing(self.valid)}{hint}"
        )

    def __str__(self) -> str:  # KeyError would add quotes around the message
        return str(self.args[0])


class ImmutableError(PincalError, AttributeError):
    """An attribute of a read-only object (a :class:`~pincal.model.Mechanism`) was set.

    Or deleted; the message names the attribute and the derivation to use instead.
    """


class MobilityError(PincalError):
    """The number of actuated joints does not match the mechanism's mobility."""


class ClosureError(PincalError):
    """A kinematic loop cannot be closed (at the home configuration or a pose)."""


class ConvergenceError(PincalError):
    """A Newton solve (forward or inverse kinematics) did not converge.

    Attributes:
        pose_index: index of the pose in the batch, or None for a single solve.
        residual: final residual norm [m or rad].
    """

    def __init__(self, message: str, pose_index: int | None = None, residual: float = float("nan")):
        self.pose_index = pose_index
        self.residual = residual
        super().__init__(message)


class SingularConfigurationError(ConvergenceError):
    """The closure Jacobian is singular at the solution (condition number reported)."""

    def __init__(
        self, message: str, pose_index: int | None = None, condition: float = float("inf")
    ):
        self.condition = condition
        super().__init__(message, pose_index=pose_index, residual=0.0)


class UnreachablePoseError(ConvergenceError):
    """An inverse-kinematics target cannot be reached (or only outside joint limits)."""


class ParameterError(PincalError):
    """Parameter values or a parameter set are inconsistent (length, names, preset)."""


class SolverOptionError(ParameterError):
    """An identification solver's option is out of range or the solver name is unknown."""


class UnidentifiableError(PincalError):
    """The parameter set is rank-deficient for the given poses and reduction was refused.

    Attributes:
        names: the parameters that are not identifiable.
    """

    def __init__(self, message: str, names: Iterable[str] = ()):
        self.names = list(names)
        super().__init__(message)


class NoTestCubeError(PincalError):
    """No ISO 9283 test cube (square) fits the workspace or the measured components."""


class TooFewPosesError(PincalError):
    """Fewer measurement equations than parameters to identify."""


class MeasurementError(PincalError):
    """Measurement data are malformed (missing columns, NaN, wrong units, ...)."""


class NoiseEstimationError(MeasurementError):
    """The measurement noise is not declared and cannot be estimated from the residuals."""


class ConditionError(MeasurementError):
    """A per-pose condition a term needs (the temperature) is missing, constant or bad."""


class VisualizationError(PincalError):
    """Inputs to a view are malformed (configuration shape, arrow, colour, ...)."""


class ReportError(PincalError):
    """Inputs to a plot or report are malformed (lengths, units, NaN, report JSON)."""


class OutputPathError(PincalError):
    """An output path would overwrite an input (or another output) of the same command."""


class ExportError(PincalError):
    """A calibration cannot be written in the asked controller format (machine kind)."""


class OptionValueError(PincalError, ValueError):
    """An option or argument value is not valid (not finite, not positive, not an integer).

    Also a ValueError, so callers that caught the plain ValueError keep working.
    """


class CalibrationDirectoryError(InputFileError):
    """A calibration directory is missing, incomplete, of a newer format or damaged."""


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


class CampaignError(InputFileError):
    """A campaign file (``pincal run``) is malformed: unknown key, bad value, missing file."""


class QualityGateError(PincalError):
    """A calibration is refused by the quality gate (units, frame, outliers, singular pose).

    Attributes:
        verdict: the :class:`pincal.identification.QualityVerdict` that refused it.
    """

    def __init__(self, message: str, verdict: object = None):
        self.verdict = verdict
        super().__init__(message)


class MissingExtraError(PincalError):
    """An optional dependency is needed and not installed (e.g. dask for ``--scheduler``)."""


class ItemFailedError(PincalError):
    """An item of an executor map failed in a worker; the message carries its error.

    Attributes:
        key: the item's key; ``error_type``: the worker's exception class name.
    """

    def __init__(self, message: str, key: str = "", error_type: str = ""):
        self.key = key
        self.error_type = error_type
        super().__init__(message)

    def __reduce__(self) -> tuple[type, tuple[str, str, str]]:
        return (type(self), (str(self), self.key, self.error_type))


class FleetFileError(InputFileError):
    """A fleet file (``pincal fleet run``) is malformed: missing key, bad unit, missing data."""
