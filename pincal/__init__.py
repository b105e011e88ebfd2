"""pincal: kinematic calibration of parallel machines and serial chains on Pinocchio.

Data flow: :func:`load_mechanism` → :func:`parameters` → pose design →
:func:`simulate_measurements` (or measured data) → :func:`identify` →
:func:`save_urdf`.
"""

from pincal.closures import COMPONENTS, Closure
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
from pincal.export import save_urdf
from pincal.identifiability import Identifiability, analyse_jacobian, identifiability
from pincal.identify import CalibrationProblem, IdentificationResult, ResidualStats, identify
from pincal.measurements import Measurements, NoiseModel, simulate_measurements
from pincal.mechanism import (
    Mechanism,
    SolverOptions,
    Workspace,
    bundled_models,
    load_mechanism,
)
from pincal.parameters import Parameter, ParameterSet, full_parameters, parameters
from pincal.sensitivity import PoseSensitivity, identification_jacobian, pose_sensitivity
from pincal.validation import PoseErrors, pose_errors
from pincal.workspace import sample_actuators, sample_pose

__version__ = "0.1.0"

__all__ = [
    "COMPONENTS",
    "CalibrationProblem",
    "Closure",
    "ClosureError",
    "ConvergenceError",
    "Identifiability",
    "IdentificationResult",
    "MeasurementError",
    "Measurements",
    "Mechanism",
    "MobilityError",
    "ModelFileError",
    "NoiseModel",
    "Parameter",
    "ParameterError",
    "ParameterSet",
    "PincalError",
    "PoseErrors",
    "PoseSensitivity",
    "ResidualStats",
    "SingularConfigurationError",
    "SolverOptions",
    "TooFewPosesError",
    "UnidentifiableError",
    "UnknownNameError",
    "UnreachablePoseError",
    "Workspace",
    "analyse_jacobian",
    "bundled_models",
    "full_parameters",
    "identifiability",
    "identification_jacobian",
    "identify",
    "load_mechanism",
    "parameters",
    "pose_errors",
    "pose_sensitivity",
    "sample_actuators",
    "sample_pose",
    "save_urdf",
    "simulate_measurements",
]
