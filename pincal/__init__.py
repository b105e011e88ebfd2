"""pincal: kinematic calibration of parallel machines and serial chains on Pinocchio.

The subpackages follow the data flow of a calibration, lowest first; a stage imports
only the stages above it in this list (``tests/test_stage_boundaries.py`` checks it):

0. :mod:`pincal.executor` — map independent work on local processes or a Dask cluster
   (imports no other stage; studies and fleets run on it);

1. :mod:`pincal.model` — load a machine (URDF + sidecar), close its loops, define parameters
   (:mod:`pincal.machines`, machine-specific closed forms, sits on the model alone);
2. :mod:`pincal.sensitivity` — identification Jacobian, identifiability, the ``base`` preset;
3. :mod:`pincal.measure` — instruments, noise, simulated measurements;
4. :mod:`pincal.design` — observability indices, candidate poses, pose selection, Cramér–Rao;
5. :mod:`pincal.identification` — identify the parameters with their covariance;
6. :mod:`pincal.compensation` — commands that reach targets with the calibrated model, and
   :mod:`pincal.validation` — held-out checks, pose errors, ISO 9283;
7. :mod:`pincal.io` — every file kind, read and written in one place;
8. :mod:`pincal.workflow` — a calibration as the commands run it, callable from Python, and
   :mod:`pincal.export` — a calibration as a controller's own kinematic parameters;
9. :mod:`pincal.report`, :mod:`pincal.viz` (loaded on first use), then :mod:`pincal.cli`.

This module exports the vocabulary of a calibration; everything else is in the subpackages.
"""

from __future__ import annotations

import importlib
from typing import Any

from pincal._version import __version__ as __version__
from pincal.compensation import Compensation, compensate
from pincal.design import (
    CramerRaoReport,
    DesignScaling,
    PoseDesign,
    candidate_set,
    cramer_rao,
    observability,
    select_poses,
)
from pincal.errors import (
    ClosureError,
    ConvergenceError,
    MeasurementError,
    MobilityError,
    ModelFileError,
    ParameterError,
    PincalError,
    SingularConfigurationError,
    UnidentifiableError,
    UnknownNameError,
    UnreachablePoseError,
)
from pincal.identification import IdentificationResult, identify
from pincal.io import (
    read_commands,
    read_measurements,
    read_poses,
    save_urdf,
    write_commands,
    write_measurements,
    write_poses,
)
from pincal.measure import (
    LaserTracker,
    Measurements,
    NoiseModel,
    simulate_measurements,
)
from pincal.model import (
    Mechanism,
    Parameter,
    ParameterSet,
    SolverOptions,
    bundled_models,
    load_mechanism,
    sample_actuators,
    serial_mechanism,
)
from pincal.sensitivity import Identifiability, identifiability, identification_jacobian, parameters
from pincal.validation import PoseErrors, pose_errors

#: names served from the plotting / meshcat subpackages, imported on first use
_LAZY = {
    "calibration_report": "pincal.report",
    "write_report": "pincal.report",
    "static_html": "pincal.viz",
    "live": "pincal.viz",
}


__all__ = [
    "ClosureError",
    "Compensation",
    "ConvergenceError",
    "CramerRaoReport",
    "DesignScaling",
    "Identifiability",
    "IdentificationResult",
    "LaserTracker",
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
    "PoseDesign",
    "PoseErrors",
    "SingularConfigurationError",
    "SolverOptions",
    "UnidentifiableError",
    "UnknownNameError",
    "UnreachablePoseError",
    "bundled_models",
    "calibration_report",
    "candidate_set",
    "compensate",
    "cramer_rao",
    "identifiability",
    "identification_jacobian",
    "identify",
    "live",
    "load_mechanism",
    "observability",
    "parameters",
    "pose_errors",
    "read_commands",
    "read_measurements",
    "read_poses",
    "sample_actuators",
    "save_urdf",
    "select_poses",
    "serial_mechanism",
    "simulate_measurements",
    "static_html",
    "write_commands",
    "write_measurements",
    "write_poses",
    "write_report",
]


def __getattr__(name: str) -> Any:
    """Load the plotting / meshcat API on first use (keeps ``import pincal`` light)."""
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'pincal' has no attribute {name!r}")
