"""Bounded reading of user files: the one way pincal opens an input.

Every input (URDF, sidecar, MJCF, CSV, JSON, YAML) is read through
:func:`read_text` or :func:`read_bytes`, which refuse non-regular files (FIFOs,
devices such as ``/dev/zero``, directories) before opening them and stop reading at a
size cap instead of exhausting memory. The cap is given per call, else it is the
``file_bytes`` of the limits in force (:class:`pincal._limits.Limits`: 200 MB unless a
block raises it; the command line sets it from ``PINCAL_MAX_FILE_MB``).
"""

from __future__ import annotations

import hashlib
import os
import stat
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path

from pincal._limits import DEFAULT_MAX_BYTES, active_limits
from pincal.errors import CalibrationDirectoryError, InputFileError, InputLimitError, clip

__all__ = [
    "DEFAULT_MAX_BYTES",
    "expected_sha256",
    "max_bytes",
    "read_bytes",
    "read_text",
    "too_big_message",
]

#: (real path, SHA-256) of files whose bytes must be those hashed (see expected_sha256)
_EXPECTED: ContextVar[tuple[tuple[str, str], ...]] = ContextVar("pincal_expected", default=())


@contextmanager
def expected_sha256(path: str | Path, digest: str) -> Iterator[None]:
    """While inside, the bytes :func:`read_bytes` reads from ``path`` must have ``digest``.

    A file checked by its SHA-256 and then read by name (a calibration's fitted data)
    could be swapped between the two; the reader compares the very bytes it parses.

    Args:
        path: the file (compared by its real path).
        digest: its expected SHA-256 (hex).
    """
    token = _EXPECTED.set((*_EXPECTED.get(), (os.path.realpath(path), digest)))
    try:
        yield
    finally:
        _EXPECTED.reset(token)


def _check_expected(p: Path, what: str, data: bytes) -> None:
    """Raise when ``p`` is expected (:func:`expected_sha256`) with other bytes than ``data``."""
    expected = _EXPECTED.get()
    if not expected:
        return
    real = os.path.realpath(p)
    for where, digest in expected:
        if where == real and hashlib.sha256(data).hexdigest() != digest:
            raise CalibrationDirectoryError(
                f"{what} {_shown(p)} changed after its SHA-256 was checked (the bytes read are "
                "not the file the calibration was fitted on); run again once nothing writes it"
            )

def max_bytes() -> int:
    """The size cap in bytes of the limits in force (default :data:`DEFAULT_MAX_BYTES`)."""
    return active_limits().file_bytes


def read_bytes(
    path: str | Path,
    what: str = "file",
    limit: int | None = None,
    error: type[InputFileError] = InputFileError,
) -> bytes:
    """Read a regular file whole, refusing devices, FIFOs and files over the cap.

    Args:
        path: file to read.
        what: what the file is, for messages ("URDF", "measurement CSV", …).
        limit: cap in bytes; ``None`` uses :func:`max_bytes`.
        error: the class raised for a missing or unreadable file (e.g.
            :class:`~pincal.errors.ModelFileError` for a URDF).

    Returns:
        The file's bytes.

    Raises:
        InputFileError: (or ``error``) the file is missing, not a regular file, or unreadable.
        InputLimitError: the file is larger than the cap.
    """
    p = Path(path)
    cap = max_bytes() if limit is None else limit
    try:
        st = p.stat()
    except FileNotFoundError:
        raise error(f"{what} {_shown(p)} does not exist") from None
    except OSError as exc:
        raise error(f"cannot read {what} {_shown(p)}: {exc.strerror}") from None
    if not stat.S_ISREG(st.st_mode):
        kind = "a directory" if stat.S_ISDIR(st.st_mode) else "not a regular file (device, FIFO, …)"
        raise error(f"{what} {_shown(p)} is {kind}; give the path of a regular file")
    if st.st_size > cap:
        raise InputLimitError(too_big_message(p, what, st.st_size, cap))
    try:
        # O_NONBLOCK: a file swapped for a FIFO after the check cannot block the open.
        fd = os.open(p, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except OSError as exc:
        raise error(f"cannot read {what} {_shown(p)}: {exc.strerror}") from None
    with os.fdopen(fd, "rb") as fh:
        data = fh.read(cap + 1)
    if len(data) > cap:
        raise InputLimitError(too_big_message(p, what, len(data), cap))
    _check_expected(p, what, data)
    return data


def read_text(
    path: str | Path,
    what: str = "file",
    limit: int | None = None,
    error: type[InputFileError] = InputFileError,
) -> str:
    """Read a regular UTF-8 text file whole (a leading BOM is dropped).

    Args:
        path: file to read.
        what: what the file is, for messages.
        limit: cap in bytes; ``None`` uses :func:`max_bytes`.
        error: the class raised for a missing, unreadable or non-UTF-8 file.

    Returns:
        The decoded text.

    Raises:
        InputFileError: (or ``error``) missing, not a regular file, unreadable or not UTF-8 (the
            message gives the byte offset of the first bad byte).
        InputLimitError: the file is larger than the cap.
    """
    data = read_bytes(path, what, limit, error)
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise error(
            f"{what} {_shown(path)} is not UTF-8 text (byte 0x{data[exc.start]:02x} at "
            f"offset {exc.start}); save it as UTF-8"
        ) from None


def _shown(path: str | Path) -> str:
    """A path for a message: whole up to 300 characters (the file name is what users need)."""
    return clip(str(path), 300)


def too_big_message(p: str | Path, what: str, size: int, cap: int) -> str:
    """The message of a file over the size cap.

    Args:
        p: the file.
        what: what the file is ("measurements file", …).
        size: its size (or the bytes read) [bytes].
        cap: the cap in force [bytes].

    Returns:
        One line naming the file, both sizes [MB] and how to raise the cap.
    """
    return (
        f"{what} {_shown(p)} is {size / 1e6:.1f} MB or more, over the {cap / 1e6:.0f} MB "
        "limit; if the file is right, raise the limit with PINCAL_MAX_FILE_MB (in Python: "
        "`with Limits(file_bytes=…).applied():`)"
    )
