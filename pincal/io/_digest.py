"""The SHA-256 of a file, how a calibration recognises the data it was fitted on."""

from __future__ import annotations

import hashlib
from pathlib import Path

from pincal._files import max_bytes, too_big_message
from pincal.errors import CalibrationDirectoryError, InputLimitError, clip

__all__ = ["sha256_file"]


def sha256_file(path: str | Path) -> str:
    """Hex SHA-256 of a file's bytes, under the input size cap every reader applies.

    Raises:
        CalibrationDirectoryError: the file is not a regular file or cannot be read.
        InputLimitError: the file is larger than the cap (:func:`pincal._files.max_bytes`):
            a huge or sparse file is refused at once, never hashed for minutes.
    """
    h = hashlib.sha256()
    if not Path(path).is_file():  # a FIFO or device would block or never end
        raise CalibrationDirectoryError(f"{clip(str(path))} is not a regular file")
    cap = max_bytes()
    size = Path(path).stat().st_size
    if size > cap:
        raise InputLimitError(too_big_message(path, "data file", size, cap))
    try:
        with open(path, "rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                h.update(block)
    except OSError as exc:
        raise CalibrationDirectoryError(f"cannot read {str(path)!r}: {exc.strerror}") from exc
    return h.hexdigest()
