"""Errors of what a call or a command is given: files, sizes, names, shapes, option values.

Files of measurement data have their own errors (:mod:`pincal.errors._measurement`).
"""

from __future__ import annotations

from collections.abc import Iterable

from pincal.errors._base import PincalError, clip, listing

__all__ = [
    "CalibrationDirectoryError",
    "CampaignError",
    "FleetFileError",
    "ImmutableError",
    "InputFileError",
    "InputLimitError",
    "ModelFileError",
    "OptionValueError",
    "OutputPathError",
    "ShapeError",
    "UnknownNameError",
]


class InputLimitError(PincalError):
    """An input is larger than a stated limit (file size, model size, option value)."""


class InputFileError(PincalError):
    """An input file is missing, not a regular file, unreadable or not UTF-8 text."""


class ModelFileError(InputFileError):
    """A URDF or sidecar file is missing, malformed or inconsistent."""


class CalibrationDirectoryError(InputFileError):
    """A calibration directory is missing, incomplete, of a newer format or damaged."""


class CampaignError(InputFileError):
    """A campaign file (``pincal run``) is malformed: unknown key, bad value, missing file."""


class FleetFileError(InputFileError):
    """A fleet file (``pincal fleet run``) is malformed: missing key, bad unit, missing data."""


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
            f"{kind} {clip(name, quote=True)} not found; {kind}s are: {listing(self.valid)}{hint}"
        )

    def __str__(self) -> str:  # KeyError would add quotes around the message
        return str(self.args[0])


class ImmutableError(PincalError, AttributeError):
    """An attribute of a read-only object (a :class:`~pincal.model.Mechanism`) was set.

    Or deleted; the message names the attribute and the derivation to use instead.
    """


class OptionValueError(PincalError, ValueError):
    """An option or argument value is not valid (not finite, not positive, not an integer).

    Also a ValueError, so callers that caught the plain ValueError keep working.
    """


class OutputPathError(PincalError):
    """An output path would overwrite an input (or another output) of the same command."""
