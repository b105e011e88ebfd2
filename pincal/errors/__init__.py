"""Exception hierarchy of pincal.

Every error a user can cause derives from :class:`PincalError`. Messages say what
was wrong and what would be valid (names, shapes, units), so the CLI can print
them as one line without a traceback. Exceptions carry the offending data as
attributes for programmatic use.

The classes live by concept in private modules and are imported from here alone
(``from pincal.errors import X``): the root and :func:`clip` (``_base``), inputs of a
call or command (``_inputs``), measurement data (``_measurement``), the model and its
solves (``_solving``), producing results (``_outputs``).
"""

from __future__ import annotations

from pincal.errors._base import (
    PincalError,
    clip,
)
from pincal.errors._inputs import (
    CalibrationDirectoryError,
    CampaignError,
    FleetFileError,
    ImmutableError,
    InputFileError,
    InputLimitError,
    ModelFileError,
    OptionValueError,
    OutputPathError,
    ShapeError,
    UnknownNameError,
)
from pincal.errors._measurement import (
    ActuatorRangeError,
    BadValueError,
    ColumnError,
    ConditionError,
    DuplicateDataError,
    FrameMismatchError,
    ImportMatchError,
    MeasurementError,
    MeasurementFileError,
    MeasurementFormatError,
    MovedTargetError,
    NoiseEstimationError,
    NonFiniteValueError,
    OrientationValueError,
    PoseFitError,
    ShiftedHeaderError,
    UnitMismatchError,
)
from pincal.errors._outputs import (
    ExportError,
    ItemFailedError,
    MissingExtraError,
    ReportError,
    VisualizationError,
    WorkerSetupError,
)
from pincal.errors._solving import (
    ClosureError,
    ConvergenceError,
    MobilityError,
    NoTestCubeError,
    ParameterError,
    QualityGateError,
    SingularConfigurationError,
    SolverOptionError,
    TooFewPosesError,
    UnidentifiableError,
    UnreachablePoseError,
)

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
    "WorkerSetupError",
    "clip",
]
