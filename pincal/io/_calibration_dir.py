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

:func:`write_calibration` writes the whole directory into a temporary sibling
(``.NAME.pincal-tmp-*``) and swaps it in with one rename, so the directory is at every
instant the complete old set or the complete new one; a lock file beside it
(``.NAME.pincal-lock``) keeps a second writer out. :func:`read_calibration` is the one
reader: a directory without a valid manifest is not a calibration, and what the
manifest lists is checked before use (see :mod:`pincal.io._calibration_checks`).
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from pincal._files import read_text
from pincal._version import __version__
from pincal.errors import CalibrationDirectoryError, PincalError, clip
from pincal.identification import IdentificationResult, result_to_dict
from pincal.io._atomic import (
    _temp_prefix,
    atomic_write_text,
    calibration_lock,
    remove_stale_temporaries,
    swap_in_directory,
)
from pincal.io._calibration_checks import (
    check_covariance,
    check_files_map,
    check_geometry,
    check_listed_file,
    check_model_files,
    check_parameters,
    hash_bounded,
    load_json,
    model_files,
    read_identification,
    read_noise,
)
from pincal.io._calibration_replace import _check_replaceable, check_replaceable
from pincal.io._file_names import (
    CALIBRATED_SIDECAR,
    CALIBRATED_URDF,
    CALIBRATION_FORMAT,
    IDENTIFICATION_FILE,
    MANIFEST,
    NOMINAL_URDF,
)
from pincal.io._urdf_export import save_urdf
from pincal.measure import NoiseModel
from pincal.model import Mechanism, load_mechanism, read_sidecar

__all__ = [
    "CALIBRATION_VERSION",
    "CalibrationDirectory",
    "check_replaceable",
    "read_calibration",
    "sha256_file",
    "write_calibration",
]

CALIBRATION_VERSION = 1


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


@dataclass(frozen=True, eq=False)
class CalibrationDirectory:
    """A calibration directory as read by :func:`read_calibration`.

    Attributes:
        path: the directory.
        manifest: the ``calibration.json`` content.
        result: the identification result (values, std, covariance (k, k) [SI]).
        calibrated_urdf: path of the calibrated URDF (its sidecar ``.yaml`` beside it).
        noise: instrument noise of the fitted data (mm, mrad), if known.
        legacy: always False (directories without a manifest are no longer read).
    """

    path: Path
    manifest: Mapping[str, Any]
    result: IdentificationResult
    calibrated_urdf: Path
    noise: NoiseModel | None = None
    legacy: bool = False
    _cache: dict = field(default_factory=dict, repr=False)

    @property
    def model(self) -> str:
        """Name of the calibrated model."""
        return str(self.manifest.get("model") or self.result.model)

    @property
    def model_source(self) -> str | None:
        """The nominal model's spec (bundled name or path) as given to ``calibrate``."""
        src = self.manifest.get("model_source")
        return str(src) if src else None

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
            try:
                self._cache["nominal"] = load_mechanism(spec)
            except PincalError as exc:
                raise CalibrationDirectoryError(
                    f"{str(self.path)!r}: cannot load the nominal model {spec!r} ({exc}); "
                    f"run from the directory calibrate was run in, or pass the model"
                ) from exc
        return self._cache["nominal"]


def _manifest(
    result: IdentificationResult,
    model_source: str | None,
    data_files: Sequence[str | Path],
    noise: NoiseModel | None,
    files: dict[str, str],
) -> dict[str, Any]:
    ident = result.identified
    return {
        "format": CALIBRATION_FORMAT,
        "version": CALIBRATION_VERSION,
        "pincal_version": __version__,
        "created": datetime.now(UTC).isoformat(timespec="seconds"),
        "model": result.model,
        "model_source": model_source,
        "model_files": model_files(model_source) if model_source else {},
        "preset": result.preset,
        "method": result.method,
        "units": {"length": "m", "angle": "rad"},
        "parameters": [
            {"name": n, "unit": u, "value": float(v), "std": float(s)}
            for n, u, v, s in zip(
                result.identified_names,
                [u for u, ok in zip(result.units, ident, strict=True) if ok],
                result.values,
                result.std,
                strict=True,
            )
        ],
        "covariance": IDENTIFICATION_FILE,
        "noise": None
        if noise is None
        else {"position_mm": float(noise.position), "orientation_mrad": float(noise.orientation)},
        "data_files": [
            {"path": str(p), "name": Path(p).name, "sha256": sha256_file(p)} for p in data_files
        ],
        "calibrated_urdf": CALIBRATED_URDF,
        "calibrated_sidecar": CALIBRATED_SIDECAR,
        "identification": IDENTIFICATION_FILE,
        "files": files,
    }


def write_calibration(
    path: str | Path,
    result: IdentificationResult,
    *,
    model_source: str | None = None,
    data_files: Sequence[str | Path] = (),
    noise: NoiseModel | None = None,
    annotations: Mapping[str, Any] | None = None,
    texts: Mapping[str, str] | None = None,
    nominal: Mechanism | None = None,
) -> CalibrationDirectory:
    """Write a calibration directory atomically (whole or absent).

    Args:
        path: the directory; an existing calibration directory (or an empty one) is
            replaced, any other existing path is refused.
        result: identification result with its calibrated mechanism.
        model_source: the nominal model spec (bundled name or path) for later commands.
        data_files: measurement files the calibration was fitted on (hashed).
        noise: instrument noise of those data (mm, mrad), if known.
        annotations: extra entries of ``identification.json`` (validation, truth, ...).
        texts: further text files to write ``{file name: content}`` (e.g. report.txt).
        nominal: the nominal mechanism to store as ``nominal.urdf`` (+ sidecar) when it
            is not ``model_source`` as loaded (a marker calibration's registered chain);
            ``annotations["markers"]`` then goes into the manifest too.

    Returns:
        The directory as :func:`read_calibration` reads it.

    Raises:
        CalibrationDirectoryError: ``path`` exists and is not a calibration directory, or
            another process is writing it (see :func:`calibration_lock`).
        ParameterError: ``result`` has no calibrated mechanism.
    """
    out = Path(path).resolve()  # "." or "cal/" name a directory we can replace by rename
    out.parent.mkdir(parents=True, exist_ok=True)
    with calibration_lock(out):
        _write_locked(out, result, model_source, data_files, noise, annotations, texts, nominal)
    return read_calibration(out)  # resolved: "." names the old directory after the swap


def _write_locked(
    out: Path,
    result: IdentificationResult,
    model_source: str | None,
    data_files: Sequence[str | Path],
    noise: NoiseModel | None,
    annotations: Mapping[str, Any] | None,
    texts: Mapping[str, str] | None,
    nominal: Mechanism | None = None,
) -> None:
    _check_replaceable(out)
    remove_stale_temporaries(out)
    mech = result.calibrated
    notes = {"data": [str(p) for p in data_files], "calibrated_urdf": CALIBRATED_URDF}
    notes.update(annotations or {})
    tmp = Path(tempfile.mkdtemp(prefix=_temp_prefix(out, "tmp"), dir=out.parent))
    try:
        save_urdf(mech, tmp / CALIBRATED_URDF)
        doc = result_to_dict(result, notes)
        atomic_write_text(tmp / IDENTIFICATION_FILE, json.dumps(doc, indent=1) + "\n")
        for name, text in (texts or {}).items():
            atomic_write_text(tmp / name, text)
        if nominal is not None:
            save_urdf(nominal, tmp / NOMINAL_URDF)
        files = {p.name: sha256_file(p) for p in sorted(tmp.iterdir()) if p.is_file()}
        manifest = _manifest(result, model_source, data_files, noise, files)
        if annotations and "quality" in annotations:  # the quality gate's verdict / override
            manifest["quality"] = annotations["quality"]
        if nominal is not None:
            manifest["nominal_urdf"] = NOMINAL_URDF
            manifest["markers"] = (annotations or {}).get("markers")
        atomic_write_text(tmp / MANIFEST, json.dumps(manifest, indent=1) + "\n")
        os.chmod(tmp, 0o755)
        _check_replaceable(out)
        swap_in_directory(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


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
