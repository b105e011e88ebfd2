"""May ``calibrate --out DIR`` replace DIR? Only when pincal wrote it (and only its files).

The manifest (``calibration.json`` with format ``pincal calibration`` and a ``files``
map) proves pincal wrote a directory. An entry it does not list, other than the files
other pincal commands put there (:data:`PINCAL_EXTRAS`), is a user's file: replacing the
directory would delete it, so the write is refused, naming it. A ``validation.json``
whose content is `pincal validate`'s (``pincal run`` writes one; the README's
``validate --out cal/validation.json``) is stale with the calibration it validated and
replaced with it. Anything else that
exists at DIR (a file, a non-empty directory without a valid manifest) is refused too.
"""

from __future__ import annotations

from pathlib import Path

from pincal.errors import CalibrationDirectoryError, PincalError, clip
from pincal.io._calibration_checks import load_json
from pincal.io._file_names import CALIBRATION_FORMAT, MANIFEST, PINCAL_EXTRAS, VALIDATION_FILE

__all__ = ["check_replaceable"]


def _manifest(out: Path) -> dict:
    """The manifest of ``out`` as :func:`load_json` reads it; {} when it is not valid."""
    try:
        return load_json(out / MANIFEST)
    except PincalError:  # unreadable, too large, not JSON, not an object
        return {}


def _validate_wrote(path: Path) -> bool:
    """Whether ``path`` (a regular file, not a link) holds `pincal validate --out`'s JSON."""
    if path.is_symlink() or not path.is_file():
        return False
    try:
        doc = load_json(path)
    except PincalError:
        return False
    return isinstance(doc.get("calibration"), dict | str) and (
        "data_sha256" in doc or "cv" in doc
    )


def check_replaceable(out: str | Path) -> None:
    """Refuse, before any work, an ``--out`` that :func:`write_calibration` would refuse.

    Raises:
        CalibrationDirectoryError: ``out`` is a file, a non-empty directory without a valid
            manifest, or a calibration directory holding files pincal did not write.
    """
    check_resolved_replaceable(Path(out).resolve())


def check_resolved_replaceable(out: Path) -> None:
    """Refuse to replace anything but a calibration directory pincal wrote, or an empty one.

    The manifest proves pincal wrote the directory; any entry it does not list (other
    than :data:`PINCAL_EXTRAS`) is a user's file and would be deleted: refused, named.
    """
    if not out.exists():
        return
    if not out.is_dir():
        raise CalibrationDirectoryError(
            f"--out {str(out)!r} exists and is not a directory; choose a new --out directory"
        )
    entries = sorted(p.name for p in out.iterdir())
    if not entries:
        return
    manifest = _manifest(out) if (out / MANIFEST).is_file() else {}
    files = manifest.get("files")
    if manifest.get("format") != CALIBRATION_FORMAT or not isinstance(files, dict):
        raise CalibrationDirectoryError(
            f"--out {str(out)!r} is a non-empty directory ({len(entries)} entries) without "
            f"a valid {MANIFEST}, so not a calibration directory pincal wrote; it is never "
            "replaced: choose a new --out directory"
        )
    foreign = [n for n in entries if n not in files and n != MANIFEST and n not in PINCAL_EXTRAS
               and not (n == VALIDATION_FILE and _validate_wrote(out / n))]  # fmt: skip
    if foreign:
        raise CalibrationDirectoryError(
            f"--out {str(out)!r} is a calibration directory that also holds files pincal did "
            f"not write ({clip(', '.join(foreign), 200)}); replacing it would delete them: "
            "move them out or choose a new --out directory"
        )
