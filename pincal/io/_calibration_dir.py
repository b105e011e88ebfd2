"""The calibration directory: what ``pincal calibrate`` and ``pincal demo`` write.

Every command that uses a calibration reads it (``view``, ``compensate``, ``validate``,
``report``).

::

    cal/
      calibration.json      manifest (format "pincal calibration", version 1)
      calibrated.urdf       calibrated model (identified geometry at full precision)
      calibrated.yaml       its sidecar (closures, actuation, measured frame, presets)
      identification.json   result_to_dict (values, std, covariance, ...)
      report.txt            optional human-readable report

The manifest holds the format version, the pincal version, the model name and source,
the parameter preset and names, the identified values and std (SI; the covariance is in
``identification.json``), units, instrument noise, the input data files with their
SHA-256 and the SHA-256 of every file of the directory, and the creation time (UTC).

:func:`pincal.io.write_calibration` (:mod:`pincal.io._calibration_write`) writes the
directory whole or not at all. :func:`read_calibration` (here) is the one reader: a
directory without a valid manifest is not a calibration, and what the manifest lists is
checked before use (see :mod:`pincal.io._calibration_checks`).
"""

from __future__ import annotations

import os
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pincal._files import expected_sha256, read_text
from pincal.errors import CalibrationDirectoryError, PincalError, clip
from pincal.identification import IdentificationRecord
from pincal.io._calibration_checks import (
    check_covariance,
    check_files_map,
    check_geometry,
    check_listed_file,
    check_model_files,
    check_parameters,
    hash_bounded,
    load_json,
    read_noise,
)
from pincal.io._digest import sha256_file
from pincal.io._file_names import (
    CALIBRATED_URDF,
    CALIBRATION_FORMAT,
    IDENTIFICATION_FILE,
    MANIFEST,
    MODEL_RECORD,
    NOMINAL_URDF,
)
from pincal.io._identification_file import read_identification
from pincal.measure import NoiseModel
from pincal.model import Mechanism, load_mechanism, read_sidecar

__all__ = ["CALIBRATION_VERSION", "CalibrationDirectory", "read_calibration"]

CALIBRATION_VERSION = 1


@dataclass(frozen=True, eq=False)
class CalibrationDirectory:
    """A calibration directory as read by :func:`read_calibration`.

    Attributes:
        path: the directory.
        manifest: the ``calibration.json`` content.
        result: the identification as recorded (values, std, covariance (k, k) [SI]);
            its mechanism is :meth:`calibrated`.
        calibrated_urdf: path of the calibrated URDF (its sidecar ``.yaml`` beside it).
        noise: instrument noise of the fitted data (mm, mrad), if known.
    """

    path: Path
    manifest: Mapping[str, Any]
    result: IdentificationRecord
    calibrated_urdf: Path
    noise: NoiseModel | None = None
    _cache: dict = field(default_factory=dict, repr=False)

    @property
    def model(self) -> str:
        """Name of the calibrated model."""
        return str(self.manifest.get("model") or self.result.model)

    @property
    def model_source(self) -> str | None:
        """The nominal model's spec (bundled name or path) as given to ``calibrate``.

        A calibration made with --sidecar, --frame or --lock holds the model with those
        options as its own hashed ``model.yaml``: that file of *this* directory, wherever
        it was copied or moved (older manifests name the first directory's).
        """
        if self._record() is not None:
            return str(self.path / MODEL_RECORD)
        src = self.manifest.get("model_source")
        if not src:
            return None
        moved = self._moved_model(str(src))
        return str(moved[0]) if moved is not None else str(src)

    def _record(self) -> dict[str, Any] | None:
        """The keys of this directory's hashed model record (``model.yaml``), or None."""
        if MODEL_RECORD not in (self.manifest.get("files") or {}):
            return None
        if "record" not in self._cache:
            self._cache["record"] = dict(read_sidecar(self.path / MODEL_RECORD))
        return self._cache["record"]

    def _recorded_model(self) -> str:
        """The model the calibration was made on as recorded: the record's robot or source."""
        record = self._record()
        if record is not None:
            return str(record.get("robot") or "")
        return str(self.manifest.get("model_source") or "")

    def model_paths(self) -> list[Path]:
        """The nominal model's files as recorded (``model_files``), where they are now.

        Their recorded paths, or where the model was moved with this directory (as
        :attr:`model_source` finds it); files that exist only. Commands treat them as
        inputs (never written over).
        """
        recorded = self.manifest.get("model_files")
        if not isinstance(recorded, dict):
            return []
        moved = self._moved_model(self._recorded_model())
        if moved is not None:
            return moved[1]
        return [f for f in (Path(str(name)) for name in recorded) if f.is_file()]

    def _moved_model(self, src: str) -> tuple[Path, list[Path]] | None:
        """The nominal model moved with this directory, every file as hashed.

        A model directory or URDF recorded by its absolute path that is gone there is
        looked for where it was relative to the calibration directory (``model_relative``:
        a project moved whole), then beside the directory under its own name; a place is
        used only when each file the manifest hashes (``model_files``) is found at the
        same place relative to it with its SHA-256.

        Returns:
            (the model's path now, each hashed file's path now, in the manifest's
            order), or None when the model was not moved so ('' for ``src``: None).
        """
        old, recorded = Path(src), self.manifest.get("model_files")
        if not src or not old.is_absolute() or old.exists() or not isinstance(recorded, dict):
            return None
        if not recorded:
            return None
        here = self.path.resolve()
        places = [here.parent / old.name]
        relative = self.manifest.get("model_relative")
        if isinstance(relative, str) and relative:
            places.insert(0, Path(os.path.normpath(here / relative)))
        for new in places:
            if not new.exists():
                continue
            root_old, root_new = (old, new) if new.is_dir() else (old.parent, new.parent)
            files = []
            for name, digest in recorded.items():
                try:
                    moved = root_new / Path(str(name)).relative_to(root_old)
                except ValueError:
                    break
                if not moved.is_file() or hash_bounded(moved) != digest:
                    break
                files.append(moved)
            else:
                return new, files
        return None

    @property
    def caveat(self) -> str | None:
        """Why this calibration must be used with care, or None.

        Set when it was written with ``--force`` past the quality gate or from a solve
        that did not succeed; commands that use the calibration print it every time.
        """
        why = []
        quality = self.manifest.get("quality")
        if isinstance(quality, dict) and quality.get("overridden"):
            why.append(f"written with --force past the quality gate ({quality.get('reason')})")
        if not self.result.success:
            why.append(f"fitted by a solve that did not succeed ({self.result.message})")
        if not why:
            return None
        return f"calibration {str(self.path)!r} was " + " and ".join(why)

    def data_file(self, index: int = 0) -> Path:
        """The data file the calibration was fitted on, found and checked by its SHA-256.

        Looked for where it was relative to the calibration directory (``relative_path``:
        a project moved or copied whole), at its absolute path when calibrate ran, beside
        the calibration directory, and where it was given (``path`` as typed, relative
        to the working directory); the first regular file whose hash matches the record
        is returned (a file of that name that differs is never used).

        Raises:
            CalibrationDirectoryError: no file recorded, none found, or every file found
                differs from the one fitted (changed since).
        """
        files = self.manifest.get("data_files") or []
        if len(files) <= index:
            raise CalibrationDirectoryError(f"{clip(str(self.path))}: the calibration records no "
                                            "data file")  # fmt: skip
        entry = files[index]
        typed = Path(str(entry.get("path", "")))
        places = [Path(str(entry.get("absolute_path") or typed)),
                  self.path.parent / typed.name, self.path / typed.name, typed]  # fmt: skip
        relative = entry.get("relative_path")
        if isinstance(relative, str) and relative:
            places.insert(0, Path(os.path.normpath(self.path.resolve() / relative)))
        found, odd = [], []
        seen: set[Path] = set()
        for p in places:  # in order, once each
            if p.absolute() in seen:
                continue
            seen.add(p.absolute())
            if p.is_file():
                if sha256_file(p) == entry.get("sha256"):
                    return p
                found.append(str(p))
            elif p.exists():  # a device, FIFO or directory is never read
                odd.append(str(p))
        if found or odd:
            verb = "differs" if len(found) == 1 else "differ"
            said = [f"{', '.join(clip(f) for f in found)} {verb} from its SHA-256 (changed "
                    "since, or another file of that name)"] if found else []  # fmt: skip
            said += [f"{', '.join(clip(f) for f in odd)}: not a regular file (device, FIFO "
                     "or directory)"] if odd else []  # fmt: skip
            raise CalibrationDirectoryError(
                f"the data file the calibration {clip(str(self.path))} was fitted on "
                f"({clip(str(typed))}) is not found: {'; '.join(said)}; restore the file "
                "(where it was relative to the calibration directory, or beside it), or "
                "re-run calibrate"
            )
        raise CalibrationDirectoryError(
            f"the data file the calibration {clip(str(self.path))} was fitted on "
            f"({clip(str(typed))}) is not found where it was relative to the calibration "
            "directory, at its absolute path, beside the directory nor where it was given; "
            "put it back where it was relative to the directory, or copy it beside it"
        )

    @contextmanager
    def reading_data_file(self, index: int = 0) -> Iterator[Path]:
        """:meth:`data_file`, its bytes checked again as they are read (no swap between).

        Yields:
            The data file; reading it inside (through :func:`pincal._files.read_bytes`,
            as every reader does) raises CalibrationDirectoryError if its bytes are not
            the ones fitted.
        """
        path = self.data_file(index)
        with expected_sha256(path, str(self.manifest["data_files"][index].get("sha256"))):
            yield path

    @property
    def preset(self) -> str:
        """Parameter preset of the identification."""
        return str(self.manifest.get("preset") or self.result.preset)

    def calibrated(self) -> Mechanism:
        """The calibrated mechanism (loaded once).

        Raises:
            ModelFileError: the URDF or sidecar does not load.
        """
        if "calibrated" not in self._cache:
            urdf = self.calibrated_urdf
            side = urdf.with_suffix(".yaml")
            text = read_text(urdf, "calibrated URDF", error=CalibrationDirectoryError)
            sidecar = read_sidecar(side) if side.is_file() else {}
            try:
                mech = Mechanism(text, sidecar, name=self.model, source=urdf)
            except PincalError as exc:
                if urdf.name in str(exc):
                    raise
                raise CalibrationDirectoryError(f"{clip(str(urdf), 200)}: {exc}") from exc
            nominal = self._nominal_if_found()
            if nominal is not None:
                check_geometry(nominal, mech, self.result, urdf)
            self._cache["calibrated"] = mech
        return self._cache["calibrated"]

    def _nominal_if_found(self) -> Mechanism | None:
        try:
            return self.nominal()
        except CalibrationDirectoryError as exc:
            if isinstance(exc.__cause__, PincalError):  # not found: nothing to check against
                return None
            raise

    def nominal(self) -> Mechanism:
        """The nominal mechanism (from ``model_source``, else the bundled model's name).

        A marker calibration stores its nominal model (the chain to the marker with the
        registered instrument frame and marker) as ``nominal.urdf``; that is read then.

        Raises:
            CalibrationDirectoryError: the nominal model cannot be found.
        """
        if "nominal" not in self._cache and self.manifest.get("nominal_urdf"):
            urdf = self.path / NOMINAL_URDF  # hashed with the other files; never a path
            side = urdf.with_suffix(".yaml")
            text = read_text(urdf, "nominal URDF", error=CalibrationDirectoryError)
            sidecar = read_sidecar(side) if side.is_file() else {}
            self._cache["nominal"] = Mechanism(text, sidecar, name=self.model, source=urdf)
        if "nominal" not in self._cache:
            spec = self.model_source or self.model
            check_model_files(self.manifest.get("model_files"), str(self.path / MANIFEST))
            record = self._record()
            moved = None if record is None else self._moved_model(self._recorded_model())
            try:
                if moved is not None and record is not None:  # the record's robot moved
                    self._cache["nominal"] = load_mechanism(str(moved[0]), sidecar=record)
                else:
                    self._cache["nominal"] = load_mechanism(spec)
            except PincalError as exc:
                raise CalibrationDirectoryError(
                    f"{str(self.path)!r}: cannot load the nominal model {spec!r} ({exc}); "
                    "put the model (with the files it was fitted on) back there or beside the "
                    "calibration directory under its name, or re-run `pincal calibrate`"
                ) from exc
        return self._cache["nominal"]


def read_calibration(path: str | Path, *, verify: bool = True) -> CalibrationDirectory:
    """Read a calibration directory (see the module doc).

    Args:
        path: the directory.
        verify: check the SHA-256 of the directory's files against the manifest.

    Returns:
        The :class:`CalibrationDirectory`.

    Raises:
        CalibrationDirectoryError: no valid manifest (then it is not a calibration), a
            file is missing, a link, too large or changed after writing (named), the
            manifest is of another format, a newer version or malformed, or the files of
            the directory disagree (values, covariance; see
            :mod:`pincal.io._calibration_checks`).
    """
    d = Path(path)
    if not d.is_dir():
        hint = (
            "; give the directory written by `pincal calibrate --out`"
            if d.suffix.lower() in (".urdf", ".yaml", ".json")
            else ""
        )
        raise CalibrationDirectoryError(f"calibration directory {str(d)!r} does not exist{hint}")
    ident_path = d / IDENTIFICATION_FILE
    if not (d / MANIFEST).is_file():
        raise CalibrationDirectoryError(
            f"{str(d)!r} is not a calibration directory: it has no {MANIFEST}, the manifest "
            f"that proves pincal wrote it (write one with `pincal calibrate MODEL --data FILE "
            f"--out {d}`)"
        )
    manifest = load_json(d / MANIFEST)
    where = str(d / MANIFEST)
    if manifest.get("format") != CALIBRATION_FORMAT:
        raise CalibrationDirectoryError(
            f"{where}: format {clip(repr(manifest.get('format')))}, expected {CALIBRATION_FORMAT!r}"
        )
    version = manifest.get("version")
    if not isinstance(version, int) or isinstance(version, bool) or version > CALIBRATION_VERSION:
        raise CalibrationDirectoryError(
            f"{where}: format version {clip(repr(version))}; this pincal reads versions ≤ "
            f"{CALIBRATION_VERSION} (upgrade pincal)"
        )
    files = check_files_map(manifest.get("files"), where, (CALIBRATED_URDF, IDENTIFICATION_FILE))
    missing = sorted(n for n in files if not (d / n).exists() and not (d / n).is_symlink())
    if missing:
        raise CalibrationDirectoryError(
            f"calibration directory {str(d)!r} is incomplete: missing {missing} "
            f"(copy the whole directory, not single files)"
        )
    for n in files:
        check_listed_file(d / n)
    if verify:
        changed = sorted(n for n, h in files.items() if hash_bounded(d / n) != h)
        if changed:
            raise CalibrationDirectoryError(
                f"calibration directory {str(d)!r}: {changed} changed after it was written "
                f"(SHA-256 mismatch); re-run `pincal calibrate` or restore the files"
            )
    result = read_identification(ident_path)
    check_parameters(manifest, result, where, IDENTIFICATION_FILE)
    check_covariance(result, str(ident_path))
    for key in ("model", "model_source", "preset"):
        if manifest.get(key) is not None and not isinstance(manifest[key], str):
            raise CalibrationDirectoryError(f"{where}: {key!r} must be a string")
    noise = read_noise(manifest.get("noise"), where)
    return CalibrationDirectory(d, manifest, result, d / CALIBRATED_URDF, noise)
