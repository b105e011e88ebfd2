"""Stage 3 — what an instrument sees.

Measurements and noise models (SI inside), scalar instruments (ballbar, sphere probe,
planes, gauge) and artefact instruments (socket plates, flush contacts) in one kind
registry, simulation, the laser tracker, instrument and marker registration.
Imports only :mod:`pincal.model` and :mod:`pincal.sensitivity`; judging a calibration
against measurements (held-out checks, pose errors, ISO 9283) is the later
:mod:`pincal.validation` stage.
"""

from __future__ import annotations

from pincal.measure._artefact_kind import Artefact, SharedTerms
from pincal.measure._flush_contact import FlushContact
from pincal.measure._instrument_kind import DeclaredConstant, HeaderValues, Instrument
from pincal.measure._instrument_kinds import Distance, Plane, Point, Sphere
from pincal.measure._instrument_registry import (
    INSTRUMENT_KINDS,
    add_instrument_kind,
    artefact_class,
    artefact_kinds,
    instrument_class,
    instrument_kinds,
)
from pincal.measure._instruments import (
    InstrumentData,
    initial_instrument_values,
    simulate_instrument,
)
from pincal.measure._marker_registration import MarkerRegistration, register_markers
from pincal.measure._markers import (
    MarkerSetup,
    marker_frame,
    marker_mechanism,
    marker_mechanisms,
)
from pincal.measure._measurements import (
    DEFAULT_NOISE,
    Measurements,
    NoiseModel,
    simulate_measurements,
)
from pincal.measure._orientation import (
    ORIENTATIONS,
    QUATERNION_TOLERANCE,
    orientation_problems,
    rotation_matrices,
)
from pincal.measure._registration import (
    Registration,
    register_instrument,
)
from pincal.measure._socket_plates import SCALE_MESSAGE
from pincal.measure._sockets import (
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

__all__ = [
    "DEFAULT_NOISE",
    "INSTRUMENT_KINDS",
    "ORIENTATIONS",
    "QUATERNION_TOLERANCE",
    "SCALE_MESSAGE",
    "Artefact",
    "DeclaredConstant",
    "Distance",
    "FlushContact",
    "HeaderValues",
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
    "PoseMeasurement",
    "Registration",
    "RigidFit",
    "SharedTerms",
    "SocketData",
    "SocketPlate",
    "Sphere",
    "TrackerNoise",
    "add_instrument_kind",
    "artefact_class",
    "artefact_kinds",
    "fit_rigid_transform",
    "initial_instrument_values",
    "instrument_class",
    "instrument_kinds",
    "marker_frame",
    "marker_mechanism",
    "marker_mechanisms",
    "orientation_problems",
    "pose_from_target_points",
    "register_instrument",
    "register_markers",
    "rigid_fit_covariance",
    "rotation_matrices",
    "simulate_instrument",
    "simulate_measurements",
    "simulate_sockets",
]
