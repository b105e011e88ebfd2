"""pincal: kinematic calibration of parallel machines and serial chains on Pinocchio."""

from pincal.errors import (
    ClosureError,
    ConvergenceError,
    MeasurementError,
    MobilityError,
    ModelFileError,
    ParameterError,
    PincalError,
    SingularConfigurationError,
    TooFewPosesError,
    UnidentifiableError,
    UnknownNameError,
    UnreachablePoseError,
)

__all__ = [
    "ClosureError",
    "ConvergenceError",
    "MeasurementError",
    "MobilityError",
    "ModelFileError",
    "ParameterError",
    "PincalError",
    "SingularConfigurationError",
    "TooFewPosesError",
    "UnidentifiableError",
    "UnknownNameError",
    "UnreachablePoseError",
]
