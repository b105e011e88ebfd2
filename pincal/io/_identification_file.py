"""``identification.json`` as a file: read bounded and parsed into an identification record."""

from __future__ import annotations

import os
from pathlib import Path

from pincal.errors import CalibrationDirectoryError, PincalError, clip
from pincal.identification import IdentificationRecord, result_from_dict
from pincal.io._calibration_checks import load_json

__all__ = ["read_identification"]


def read_identification(path: str | os.PathLike) -> IdentificationRecord:
    """Read an ``identification.json`` (the one reader of the file kind).

    Read bounded (50 MB, no FIFOs or devices) and parsed by
    :func:`pincal.identification.result_from_dict`: the record of the identification (no
    parameter set or mechanism: ``record.applied_to(nominal)`` gives the calibrated one),
    its context in ``annotations``.

    Raises:
        CalibrationDirectoryError: missing, unreadable, not a JSON object, of a newer
            format version or written by pincal 0.1, or malformed (the message names the file and
            what is wrong).
    """
    path = Path(path)
    try:
        return result_from_dict(load_json(path), source=str(path))
    except CalibrationDirectoryError:
        raise
    except PincalError as exc:
        raise CalibrationDirectoryError(str(exc)) from exc
    except (TypeError, ValueError, KeyError, AttributeError, IndexError) as exc:
        raise CalibrationDirectoryError(
            f"{str(path)!r} is malformed ({type(exc).__name__}: {clip(str(exc), 120)}); "
            "re-run `pincal calibrate`"
        ) from None
