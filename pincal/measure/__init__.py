"""Stage 3 — what an instrument sees.

Measurements and noise models (SI inside), scalar instruments (ballbar, sphere probe,
planes, gauge), ISO 9283 pose characteristics, simulation, the laser tracker, instrument
registration, pose errors against a reference, validation on held-out data.
"""

from __future__ import annotations

from pincal.measure._held_out import (
    PREDICTION_BOUNDS,
    HeldOutValidation,
    prediction_caveat,
    validate_held_out,
)
from pincal.measure._instrument_kind import HeaderValues, Instrument
from pincal.measure._instrument_kinds import Distance, Plane, Point, Sphere
from pincal.measure._instrument_registry import (
    INSTRUMENT_KINDS,
    add_instrument_kind,
    instrument_class,
    instrument_kinds,
)
from pincal.measure._instruments import (
    InstrumentData,
    initial_instrument_values,
    simulate_instrument,
)
from pincal.measure._iso9283 import (
    ORIENTATION_CONVENTION,
    PointAccuracy,
    PoseCharacteristics,
    point_accuracy,
    pose_characteristics,
    simulate_cycles,
)
from pincal.measure._iso_cube import (
    TestCube,
    iso_test_cube,
)
from pincal.measure._markers import (
    MarkerRegistration,
    MarkerSetup,
    marker_frame,
    marker_mechanism,
    marker_mechanisms,
    register_markers,
)
from pincal.measure._measurements import (
    DEFAULT_NOISE,
    Measurements,
    NoiseModel,
    simulate_measurements,
)
from pincal.measure._registration import (
    Registration,
    register_instrument,
)
from pincal.measure._sockets import (
    SCALE_MESSAGE,
    KnownDistance,
    SocketData,
    SocketPlate,
    simulate_sockets,
)
from pincal.measure._tracker import (
    LaserTracker,
    PoseMeasurement,
    RigidFit,
    TrackerNoise,
    fit_rigid_transform,
    pose_from_target_points,
    rigid_fit_covariance,
)
from pincal.measure._validation import (
    PoseErrors,
    pose_errors,
)

__all__ = [
    "DEFAULT_NOISE",
    "INSTRUMENT_KINDS",
    "ORIENTATION_CONVENTION",
    "PREDICTION_BOUNDS",
    "SCALE_MESSAGE",
    "Distance",
    "HeaderValues",
    "HeldOutValidation",
    "Instrument",
    "InstrumentData",
    "KnownDistance",
    "LaserTracker",
    "MarkerRegistration",
    "MarkerSetup",
    "Measurements",
    "NoiseModel",
    "Plane",
    "Point",
    "PointAccuracy",
    "PoseCharacteristics",
    "PoseErrors",
    "PoseMeasurement",
    "Registration",
    "RigidFit",
    "SocketData",
    "SocketPlate",
    "Sphere",
    "TestCube",
    "TrackerNoise",
    "add_instrument_kind",
    "fit_rigid_transform",
    "initial_instrument_values",
    "instrument_class",
    "instrument_kinds",
    "iso_test_cube",
    "marker_frame",
    "marker_mechanism",
    "marker_mechanisms",
    "point_accuracy",
    "pose_characteristics",
    "pose_errors",
    "pose_from_target_points",
    "prediction_caveat",
    "register_instrument",
    "register_markers",
    "rigid_fit_covariance",
    "simulate_cycles",
    "simulate_instrument",
    "simulate_measurements",
    "simulate_sockets",
    "validate_held_out",
]
