"""Per-item results on disk, each written atomically: a resumed executor map reuses them.

:class:`ResultStore` is the :class:`pincal.executor.Store` of ``pincal fleet run``.
"""

from __future__ import annotations

import hashlib
import os
import pickle
import re
from pathlib import Path
from typing import Any

from pincal.errors import OutputPathError, clip
from pincal.io._atomic import atomic_write_bytes

__all__ = ["ResultStore"]

_SAFE = re.compile(r"[^A-Za-z0-9_.-]")


class ResultStore:
    """A directory of pickled item results, one file per key.

    A result is written through a temporary file and ``os.replace``
    (:func:`atomic_write_bytes`): a run killed mid-write leaves the previous state, never
    half a file. Only successful results are stored, so a rerun computes again exactly
    the items that failed or never ran.

    Args:
        path: the directory (created when missing).
    """

    def __init__(self, path: str | os.PathLike[str]):
        self.path = Path(path)
        if self.path.exists() and not self.path.is_dir():
            raise OutputPathError(
                f"result store {clip(str(self.path))} is a file: give a directory (it is "
                "created when missing)"
            )
        self.path.mkdir(parents=True, exist_ok=True)

    def file(self, key: str) -> Path:
        """The file of ``key``: its safe characters plus a short digest (keys stay distinct)."""
        digest = hashlib.sha256(key.encode("utf-8")).hexdigest()[:12]
        return self.path / f"{_SAFE.sub('_', key)[:80]}.{digest}.pkl"

    def has(self, key: str) -> bool:
        """Whether a result of ``key`` is written."""
        return self.file(key).is_file()

    def load(self, key: str) -> Any:
        """The stored result of ``key`` (KeyError when none is written)."""
        try:
            blob = self.file(key).read_bytes()
        except FileNotFoundError:
            raise KeyError(key) from None
        return pickle.loads(blob)

    def save(self, key: str, value: Any) -> None:
        """Write ``value`` as the result of ``key``, whole or not at all."""
        atomic_write_bytes(self.file(key), pickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL))
