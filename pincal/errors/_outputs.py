"""Errors of producing results: views, reports, controller exports and running the work.

Running the work: an optional dependency that is not installed, workers that cannot
load the work they are sent, an item that failed in a worker of an executor map.
"""

from __future__ import annotations

from pincal.errors._base import PincalError

__all__ = [
    "ExportError",
    "ItemFailedError",
    "MissingExtraError",
    "ReportError",
    "VisualizationError",
    "WorkerSetupError",
]


class VisualizationError(PincalError):
    """Inputs to a view are malformed (configuration shape, arrow, colour, ...)."""


class ReportError(PincalError):
    """Inputs to a plot or report are malformed (lengths, units, NaN, report JSON)."""


class ExportError(PincalError):
    """A calibration cannot be written in the asked controller format (machine kind)."""


class MissingExtraError(PincalError):
    """An optional dependency is needed and not installed (e.g. dask for ``--scheduler``)."""


class WorkerSetupError(PincalError):
    """The Dask workers cannot load the work they are sent (a module missing there)."""


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
