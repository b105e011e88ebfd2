"""Atomic file output: a file is written whole or not at all; directories swapped whole.

Files go through a temporary file in the same directory and one ``os.replace``.
Directories (the calibration directory) are written into a temporary sibling named
``.NAME.pincal-tmp-*`` and swapped in by :func:`exchange_paths`; a lock file
``.NAME.pincal-lock`` beside the directory (:func:`calibration_lock`) keeps a second
writer out. Temporaries a killed run left behind are recognised by their names and
removed by the next writer (:func:`remove_stale_temporaries`).
"""

from __future__ import annotations

import ctypes
import errno
import glob
import os
import shutil
import stat
import sys
import tempfile
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from pincal.errors import CalibrationDirectoryError, OutputPathError, clip
from pincal.io._file_names import MANIFEST

__all__ = [
    "atomic_write_bytes",
    "atomic_write_text",
    "calibration_lock",
    "exchange_paths",
    "output_target",
    "remove_stale_temporaries",
    "swap_in_directory",
]

_RENAME_EXCHANGE = 2  # linux/fs.h
_held: dict[Path, tuple[int, int]] = {}  # lock path -> (fd, depth) held by this process
_held_guard = threading.Lock()


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # exists, owned by someone else
        return True
    return True


def _remove_dead_writers_temporaries(path: Path) -> None:
    """Remove ``.NAME.<pid>.*.tmp`` beside ``path`` left by writers that were killed."""
    for stale in path.parent.glob(f".{glob.escape(path.name)}.*.tmp"):
        pid = stale.name[len(path.name) + 2 :].split(".", 1)[0]
        if pid.isdigit() and not _pid_alive(int(pid)):
            stale.unlink(missing_ok=True)


def _link_in_calibration(path: Path) -> tuple[Path, Path] | None:
    """The first symbolic link on ``path`` below a calibration directory, and that directory.

    A calibration directory is one holding a manifest; the file itself and every
    directory between it and the calibration directory are checked (a received
    directory may hold ``report.md -> ~/.bashrc`` or ``sub -> ~``). Links above the
    calibration directory are the user's own and are followed.

    Returns:
        (the link, the calibration directory), or None.
    """
    full = Path(os.path.abspath(path))
    chain = [*reversed(full.parents), full]  # the root first
    for k, above in enumerate(chain[:-1]):
        if (above / MANIFEST).is_file():
            for below in chain[k + 1 :]:
                if below.is_symlink():
                    return below, above
            return None
    return None


def output_target(path: str | Path, what: str = "output") -> Path:
    """The regular file an output named ``path`` is written to.

    An absent path or a regular file is written as named. A symbolic link is never
    replaced: the file it points to is written instead (so ``--out link.csv`` updates
    the linked file and keeps the link) — except inside a calibration directory (one
    holding a manifest), where a link is refused, the file's or a directory's between
    it and the calibration directory: a received directory could point ``report.md``
    (or a sub-directory) at any file of the user's. Devices, FIFOs, sockets, directories, links to
    them and dangling links are refused: replacing them would turn ``/dev/null`` or
    ``/dev/stdout`` into a regular file. Nothing under ``/dev`` or ``/proc`` is written.

    Args:
        path: the output path.
        what: what names it in messages (e.g. ``"--out"``).

    Raises:
        OutputPathError: the path names something other than a regular file.
    """
    p = Path(path)
    target = p
    fix = "outputs are written only to regular files: give the path of a file"
    if Path(os.path.abspath(p)).parts[1:2] in (("dev",), ("proc",)):
        raise OutputPathError(f"{what} {clip(str(p), 300)} is under /dev or /proc; {fix}")
    planted = _link_in_calibration(p)
    if planted is not None:
        link, home = planted
        where = ("is" if link == Path(os.path.abspath(p))
                 else f"passes through {clip(str(link), 200)},")  # fmt: skip
        raise OutputPathError(
            f"{what} {clip(str(p), 300)} {where} a symbolic link inside the calibration "
            f"directory {clip(str(home), 200)}; pincal never writes through a link there (it "
            "could point anywhere): remove the link, or write elsewhere"
        )
    if p.is_symlink():
        try:
            target = p.resolve(strict=True)
        except (FileNotFoundError, RuntimeError, OSError):
            raise OutputPathError(
                f"{what} {clip(str(p), 300)} is a symbolic link to a missing file (or a "
                "link loop); pincal never replaces a link: remove it or give another path"
            ) from None
    try:
        st = os.stat(target)
    except FileNotFoundError:
        st = None
    except OSError as exc:
        raise OutputPathError(f"cannot write {what} {clip(str(p), 300)}: {exc.strerror}") from None
    system = Path(os.path.abspath(target)).parts[1:2] in (("dev",), ("proc",))
    if system or (st is not None and not stat.S_ISREG(st.st_mode)):
        kind = (
            "a file under /dev or /proc" if system
            else "a directory" if stat.S_ISDIR(st.st_mode)  # type: ignore[union-attr]
            else "a device, FIFO or socket"
        )  # fmt: skip
        via = f" (the link points to {clip(str(target), 200)})" if target != p else ""
        raise OutputPathError(f"{what} {clip(str(p), 300)} is {kind}{via}; {fix}")
    return target


def atomic_write_bytes(path: str | Path, data: bytes, *, durable: bool = True) -> Path:
    """Write ``data`` to ``path`` through a temporary file in the same directory.

    The temporary is named ``.NAME.<pid>.XXXX.tmp``; those of writers no longer running
    (killed by SIGKILL, so their cleanup never ran) are removed here. ``durable=False``
    skips the fsync (a few ms per file): for scratch files read back and deleted.
    A symbolic link is written through to its target (see :func:`output_target`).

    Raises:
        OutputPathError: ``path`` is a device, FIFO, directory, or a link to one.
    """
    path = output_target(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    _remove_dead_writers_temporaries(path)
    fd, tmp = tempfile.mkstemp(
        prefix=f".{path.name}.{os.getpid()}.", suffix=".tmp", dir=path.parent
    )
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            if durable:
                os.fsync(fh.fileno())
        os.chmod(tmp, 0o644)  # mkstemp creates 0600; outputs are meant to be shared
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def atomic_write_text(path: str | Path, text: str) -> Path:
    """Write UTF-8 ``text`` to ``path`` atomically."""
    return atomic_write_bytes(path, text.encode("utf-8"))


def temp_prefix(out: Path, kind: str) -> str:
    """Name prefix of the temporaries of directory ``out`` ("tmp" or "old")."""
    return f".{out.name}.pincal-{kind}-"


def exchange_paths(a: Path, b: Path) -> bool:
    """Atomically exchange two existing paths (Linux ``renameat2(RENAME_EXCHANGE)``).

    Returns:
        True when exchanged; False when the platform or file system cannot (the caller
        then falls back to two renames).
    """
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        renameat2 = libc.renameat2
    except (OSError, AttributeError):
        return False
    at_fdcwd = -100
    rc = renameat2(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), _RENAME_EXCHANGE)
    if rc == 0:
        return True
    err = ctypes.get_errno()
    if err in (errno.ENOSYS, errno.EINVAL, errno.ENOTSUP):
        return False
    raise OSError(err, os.strerror(err), str(b))


def swap_in_directory(tmp: Path, out: Path) -> None:
    """Put the finished directory ``tmp`` at ``out``, replacing what is there.

    On Linux the swap is one ``renameat2(RENAME_EXCHANGE)``, so ``out`` is at every
    instant either the complete old directory or the complete new one; the old one
    ends up in ``tmp`` and is removed. Elsewhere the old directory is first moved aside
    (``.NAME.pincal-old-*``).
    """
    if not out.exists():
        os.replace(tmp, out)
        return
    if exchange_paths(tmp, out):
        shutil.rmtree(tmp, ignore_errors=True)
        return
    old = Path(tempfile.mkdtemp(prefix=temp_prefix(out, "old"), dir=out.parent))
    os.replace(out, old / out.name)
    try:
        os.replace(tmp, out)
    except BaseException:
        os.replace(old / out.name, out)
        raise
    shutil.rmtree(old, ignore_errors=True)


def remove_stale_temporaries(out: Path) -> list[Path]:
    """Remove the temporaries an interrupted writer of ``out`` left beside it.

    Call only while holding :func:`calibration_lock` (no other writer is running).

    Returns:
        The removed paths.
    """
    removed = []
    for kind in ("tmp", "old"):
        for stale in out.parent.glob(temp_prefix(out, kind) + "*"):
            if stale.is_dir() and not stale.is_symlink():
                shutil.rmtree(stale, ignore_errors=True)
            else:
                stale.unlink(missing_ok=True)
            removed.append(stale)
    return removed


def _lock_path(out: Path) -> Path:
    return out.parent / f".{out.name}.pincal-lock"


def _acquire(lock: Path, out: Path) -> int:
    import fcntl

    while True:
        try:  # O_NOFOLLOW: a planted link (dangling: O_CREAT would create its target)
            fd = os.open(lock, os.O_RDWR | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0), 0o644)
        except OSError as exc:
            if exc.errno != errno.ELOOP:
                raise
            raise CalibrationDirectoryError(
                f"the lock file {str(lock)!r} of {str(out)!r} is a symbolic link; pincal "
                "never opens a link there (it could point anywhere): remove it"
            ) from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(fd)
            raise CalibrationDirectoryError(
                f"another pincal is writing the calibration directory {str(out)!r} (lock "
                f"{lock.name!r} is held); wait for it to finish or choose another --out"
            ) from None
        except BaseException:
            os.close(fd)
            raise
        try:  # the holder before us may have removed the file: lock the current one
            if os.stat(lock).st_ino == os.fstat(fd).st_ino:
                return fd
        except FileNotFoundError:
            pass
        os.close(fd)


@contextmanager
def calibration_lock(path: str | Path) -> Iterator[Path]:
    """Hold the writer's lock of calibration directory ``path`` (re-entrant per process).

    The lock is an ``flock`` on ``.NAME.pincal-lock`` beside the directory, released
    (and the file removed) on exit; the kernel releases it when the process dies.

    Yields:
        The resolved directory path.

    Raises:
        CalibrationDirectoryError: another process holds the lock.
    """
    out = Path(path).resolve()
    out.parent.mkdir(parents=True, exist_ok=True)
    lock = _lock_path(out)
    if sys.platform == "win32":  # pragma: no cover - no flock; single-writer assumed
        yield out
        return
    with _held_guard:
        if lock in _held:
            fd, depth = _held[lock]
            _held[lock] = (fd, depth + 1)
        else:
            _held[lock] = (_acquire(lock, out), 1)
    try:
        yield out
    finally:
        with _held_guard:
            fd, depth = _held[lock]
            if depth > 1:
                _held[lock] = (fd, depth - 1)
            else:
                del _held[lock]
                lock.unlink(missing_ok=True)
                os.close(fd)
