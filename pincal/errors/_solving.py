"""Errors of the model and its solves: assembly, kinematics, parameters, identification.

A mechanism that cannot be assembled or closed, a kinematic solve that does not
converge, an inconsistent parameter set, an identification that cannot be made
(too few poses, unidentifiable parameters) or that the quality gate refuses.
"""

from __future__ import annotations

from collections.abc import Iterable

from pincal.errors._base import PincalError

__all__ = [
    "ClosureError",
    "ConvergenceError",
    "MobilityError",
    "NoTestCubeError",
    "ParameterError",
    "QualityGateError",
    "SingularConfigurationError",
    "SolverOptionError",
    "TooFewPosesError",
    "UnidentifiableError",
    "UnreachablePoseError",
]


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


class QualityGateError(PincalError):
    """A calibration is refused by the quality gate (units, frame, outliers, singular pose).

    Attributes:
        verdict: the :class:`pincal.identification.QualityVerdict` that refused it.
    """

    def __init__(self, message: str, verdict: object = None):
        self.verdict = verdict
        super().__init__(message)
