"""The SHA-256 of a file, how a calibration recognises the data it was fitted on."""

from __future__ import annotations

import hashlib
import os
import stat
from pathlib import Path
from typing import BinaryIO

from pincal._files import max_bytes, too_big_message
from pincal.errors import CalibrationDirectoryError, InputLimitError, clip

__all__ = ["hash_stream", "sha256_file"]


def sha256_file(path: str | Path) -> str:
    """Hex SHA-256 of a file's bytes, under the input size cap every reader applies.

    Raises:
        CalibrationDirectoryError: the file is not a regular file or cannot be read.
        InputLimitError: the file is larger than the cap (:func:`pincal._files.max_bytes`):
            a huge or sparse file is refused at once, never hashed for minutes.
    """
    cap = max_bytes()
    try:
        # O_NONBLOCK: a file swapped for a FIFO after any earlier check cannot block the
        # open; what is checked is the file opened (fstat), not the name
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except OSError as exc:
        raise CalibrationDirectoryError(f"cannot read {str(path)!r}: {exc.strerror}") from exc
    with os.fdopen(fd, "rb") as fh:
        st = os.fstat(fh.fileno())
        if not stat.S_ISREG(st.st_mode):  # a FIFO or device would block or never end
            raise CalibrationDirectoryError(f"{clip(str(path))} is not a regular file")
        if st.st_size > cap:
            raise InputLimitError(too_big_message(path, "data file", st.st_size, cap))
        try:
            digest, more = hash_stream(fh, cap)
        except OSError as exc:
            raise CalibrationDirectoryError(f"cannot read {str(path)!r}: {exc.strerror}") from exc
    if more:
        raise InputLimitError(too_big_message(path, "data file", cap + 1, cap))
    return digest


def hash_stream(fh: BinaryIO, limit: int) -> tuple[str, bool]:
    """(hex SHA-256 of at most ``limit`` + 1 bytes [B] of an open file, more than ``limit``).

    Bounded so that a file growing while it is read cannot make the read unbounded.
    """
    h = hashlib.sha256()
    left = limit + 1
    while left > 0 and (block := fh.read(min(1 << 20, left))):
        h.update(block)
        left -= len(block)
    return h.hexdigest(), left <= 0
