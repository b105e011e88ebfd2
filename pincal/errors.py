"""Exception hierarchy of pincal.

Every error a user can cause derives from :class:`PincalError`. Messages say what
was wrong and what would be valid (names, shapes, units), so the CLI can print
them as one line without a traceback. Exceptions carry the offending data as
attributes for programmatic use.
"""

from __future__ import annotations

from collections.abc import Iterable

__all__ = [
    "ClosureError",
    "ConvergenceError",
    "MeasurementError",
    "MobilityError",
    "ModelFileError",
    "ParameterError",
    "PincalError",
    "ReportError",
    "SingularConfigurationError",
    "TooFewPosesError",
    "UnidentifiableError",
    "UnknownNameError",
    "UnreachablePoseError",
    "VisualizationError",
]


class PincalError(Exception):
    """Root of all pincal errors."""


def _listing(names: Iterable[str], limit: int = 40) -> str:
    names = list(names)
    shown = ", ".join(repr(n) for n in names[:limit])
    if len(names) > limit:
        shown += f", … ({len(names) - limit} more)"
    return shown


class ModelFileError(PincalError):
    """A URDF or sidecar file is missing, malformed or inconsistent."""


class UnknownNameError(PincalError, KeyError):
    """A frame, joint, parameter or preset name does not exist.

    Attributes:
        kind: what was looked up ("frame", "joint", "preset", ...).
        name: the name that was not found.
        valid: the names that would have been accepted.
    """

    def __init__(self, kind: str, name: str, valid: Iterable[str]):
        self.kind = kind
        self.name = name
        self.valid = list(valid)
        super().__init__(f"{kind} {name!r} not found; {kind}s are: {_listing(self.valid)}")

    def __str__(self) -> str:  # KeyError would add quotes around the message
        return str(self.args[0])


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


class UnidentifiableError(PincalError):
    """The parameter set is rank-deficient for the given poses and reduction was refused.

    Attributes:
        names: the parameters that are not identifiable.
    """

    def __init__(self, message: str, names: Iterable[str] = ()):
        self.names = list(names)
        super().__init__(message)


class TooFewPosesError(PincalError):
    """Fewer measurement equations than parameters to identify."""


class MeasurementError(PincalError):
    """Measurement data are malformed (missing columns, NaN, wrong units, ...)."""


class VisualizationError(PincalError):
    """Inputs to a view are malformed (configuration shape, arrow, colour, ...)."""


class ReportError(PincalError):
    """Inputs to a plot or report are malformed (lengths, units, NaN, report JSON)."""
