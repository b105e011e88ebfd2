"""The SHA-256 of a file, how a calibration recognises the data it was fitted on."""

from __future__ import annotations

import hashlib
from pathlib import Path

from pincal.errors import CalibrationDirectoryError, clip

__all__ = ["sha256_file"]


def sha256_file(path: str | Path) -> str:
    """Hex SHA-256 of a file's bytes.

    Raises:
        CalibrationDirectoryError: the file cannot be read.
    """
    h = hashlib.sha256()
    if not Path(path).is_file():  # a FIFO or device would block or never end
        raise CalibrationDirectoryError(f"{clip(str(path))} is not a regular file")
    try:
        with open(path, "rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                h.update(block)
    except OSError as exc:
        raise CalibrationDirectoryError(f"cannot read {str(path)!r}: {exc.strerror}") from exc
    return h.hexdigest()
