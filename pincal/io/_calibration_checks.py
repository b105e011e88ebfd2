"""Checks that a calibration directory tells the truth, run when it is read.

A directory is a calibration only with a valid manifest (``calibration.json``); its
``files`` map lists plain file names inside the directory (no ``/``, ``..``, hidden or
absolute names, no symbolic links) with their SHA-256, each file at most
:func:`pincal._files.max_bytes` large (so no listed file can make a read hang or reach
outside the directory). After the hashes, the contents are cross-checked:

* the manifest's parameter names and values equal ``identification.json``'s;
* the covariance is finite, symmetric and positive semi-definite, and ``std`` is the
  square root of its diagonal;
* ``calibrated.urdf`` is the nominal model with the identified values applied (when the
  nominal model can be loaded), and the nominal model's files have the SHA-256 recorded
  when the calibration was written (``model_files``).
"""

from __future__ import annotations

import json
import os
import re
import stat
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from pincal._files import max_bytes, read_text
from pincal.errors import CalibrationDirectoryError, ParameterError, PincalError, clip
from pincal.identification import IdentificationRecord
from pincal.io._digest import hash_stream
from pincal.measure import NoiseModel
from pincal.model import resolve_model_path

if TYPE_CHECKING:
    from pincal.model import Mechanism

__all__ = [
    "check_covariance",
    "check_files_map",
    "check_geometry",
    "check_listed_file",
    "check_parameters",
    "hash_bounded",
    "load_json",
    "model_files",
    "read_noise",
]

_MAX_JSON_BYTES = 50_000_000
_HEX64 = re.compile(r"[0-9a-f]{64}")
#: agreement of the manifest's values with identification.json, and of calibrated.urdf's
#: joint origins with the nominal model displaced by them (both are written at full
#: precision: the tolerance only absorbs the rounding of a re-computation)
_VALUE_RTOL = 1e-9
_ORIGIN_TOL = 1e-9  # m / rad
_CORR_ASYMMETRY = 1e-2
_EIG_TOL = 1e-6


def _plain_name(name: object) -> bool:
    if not isinstance(name, str) or not name or name in (".", ".."):
        return False
    return "/" not in name and "\\" not in name and "\0" not in name and not name.startswith(".")


def check_files_map(files: object, where: str, required: tuple[str, ...]) -> dict[str, str]:
    """The manifest's ``files`` map, checked: plain names, SHA-256 hex digests.

    Raises:
        CalibrationDirectoryError: not a map, a name that is not a plain file name of the
            directory, a value that is not a SHA-256, or a required file not listed.
    """
    if not isinstance(files, dict) or not files:
        raise CalibrationDirectoryError(
            f"{where}: 'files' must map each file of the directory to its SHA-256; got "
            f"{clip(repr(files))}. A directory without a valid manifest is not a "
            "calibration: re-run `pincal calibrate`"
        )
    bad = [n for n in files if not _plain_name(n)]
    if bad:
        raise CalibrationDirectoryError(
            f"{where}: 'files' lists {clip(repr(bad[0]), 80)}, which is not a plain file "
            "name inside the directory (no '/', '..', leading '.' or absolute path); "
            "re-run `pincal calibrate`"
        )
    wrong = [n for n, h in files.items() if not (isinstance(h, str) and _HEX64.fullmatch(h))]
    if wrong:
        raise CalibrationDirectoryError(
            f"{where}: 'files' gives {clip(repr(files[wrong[0]]), 80)} for {wrong[0]!r}; "
            "each value must be a 64-digit lowercase hex SHA-256"
        )
    unlisted = [n for n in required if n not in files]
    if unlisted:
        raise CalibrationDirectoryError(
            f"{where}: 'files' does not list {unlisted}, which every calibration holds; "
            "re-run `pincal calibrate`"
        )
    return dict(files)


def check_listed_file(path: Path) -> int:
    """Size of the listed file ``path``: a regular file (not a link) within the size cap.

    Raises:
        CalibrationDirectoryError: missing, a link, not a regular file, or too large.
    """
    shown = f"{path.name!r} in {clip(str(path.parent), 200)}"
    try:
        st = os.lstat(path)
    except OSError as exc:
        raise CalibrationDirectoryError(f"cannot read {shown}: {exc.strerror}") from None
    if not stat.S_ISREG(st.st_mode):
        kind = "a symbolic link" if stat.S_ISLNK(st.st_mode) else "not a regular file"
        raise CalibrationDirectoryError(
            f"{shown} is {kind}; a calibration directory holds regular files only "
            "(copy the directory with its files, not links)"
        )
    cap = max_bytes()
    if st.st_size > cap:
        raise CalibrationDirectoryError(
            f"{shown} is {st.st_size / 1e6:.1f} MB, over the {cap / 1e6:.0f} MB "
            "limit of one file; if it is right, raise the limit with PINCAL_MAX_FILE_MB"
        )
    return st.st_size


def hash_bounded(path: Path) -> str:
    """SHA-256 of the listed file ``path`` (checked by :func:`check_listed_file` first)."""
    size = check_listed_file(path)
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOFOLLOW", 0))
    with os.fdopen(fd, "rb") as fh:
        return hash_stream(fh, size)[0]  # (a file grown since hashes otherwise)


def check_parameters(
    manifest: Mapping[str, Any], result: IdentificationRecord, where: str, ident: str
) -> None:
    """The manifest's parameter names and values equal ``identification.json``'s.

    Raises:
        CalibrationDirectoryError: a malformed ``parameters`` list or a disagreement.
    """
    entries = manifest.get("parameters", [])
    if not isinstance(entries, list) or not all(isinstance(p, dict) for p in entries):
        raise CalibrationDirectoryError(
            f"{where}: 'parameters' must be a list of {{name, unit, value, std}} objects"
        )
    if not entries:
        return
    names = [p.get("name") for p in entries]
    if tuple(names) != tuple(result.identified_names):
        raise CalibrationDirectoryError(
            f"{where}: parameters {clip(repr(names[:3]), 120)}… differ from {ident}'s "
            f"{clip(repr(list(result.identified_names[:3])), 120)}…; the files of the "
            "directory disagree: re-run `pincal calibrate`"
        )
    try:
        values = np.array([float(p.get("value")) for p in entries])  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise CalibrationDirectoryError(
            f"{where}: each parameter needs a numeric 'value' (SI: m, rad)"
        ) from None
    ours = np.asarray(result.values, dtype=float)
    off = ~np.isclose(values, ours, rtol=_VALUE_RTOL, atol=1e-15)
    if off.any():
        k = int(np.argmax(off))
        raise CalibrationDirectoryError(
            f"{where}: parameter {names[k]!r} is {float(values[k])!r} but {ident} gives "
            f"{float(ours[k])!r}; the files of the directory disagree: re-run `pincal calibrate`"
        )


def check_covariance(result: IdentificationRecord, ident: str) -> None:
    """The covariance is a covariance, and ``std`` the root of its diagonal.

    Raises:
        CalibrationDirectoryError: not finite, not symmetric, not positive semi-definite,
            or ``std`` disagrees with it (the message gives the largest offence).
    """
    cov = np.asarray(result.covariance, dtype=float)
    std = np.asarray(result.std, dtype=float)
    if cov.size == 0:
        return
    fix = "re-run `pincal calibrate`"
    if not np.all(np.isfinite(cov)):
        raise CalibrationDirectoryError(f"{ident}: the covariance has non-finite entries; {fix}")
    diag = np.diag(cov)
    if np.any(diag < 0):
        k = int(np.argmin(diag))
        raise CalibrationDirectoryError(
            f"{ident}: the covariance gives {result.identified_names[k]!r} the negative "
            f"variance {diag[k]:.3g}; a variance is ≥ 0: {fix}"
        )
    # in correlation units (scale-free): an ill-conditioned inverse is symmetric only to
    # ~1e-3 there, so only gross asymmetry and clearly negative directions are refused
    s = np.sqrt(diag)
    s[s == 0] = 1.0
    corr = cov / np.outer(s, s)
    asym = float(np.max(np.abs(corr - corr.T)))
    if asym > _CORR_ASYMMETRY:
        raise CalibrationDirectoryError(
            f"{ident}: the covariance is not symmetric (largest correlation difference "
            f"{asym:.3g}); {fix}"
        )
    eig = np.linalg.eigvalsh(0.5 * (corr + corr.T))
    if eig[0] < -_EIG_TOL * max(float(eig[-1]), 1.0):
        raise CalibrationDirectoryError(
            f"{ident}: the covariance is not positive semi-definite (smallest eigenvalue of "
            f"the correlation matrix {eig[0]:.3g}); a covariance has no negative variance "
            f"in any direction: {fix}"
        )
    root = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    if std.shape == root.shape and np.all(np.isfinite(std)):
        bad = ~np.isclose(std, root, rtol=1e-6, atol=1e-300)
        if bad.any():
            k = int(np.argmax(bad))
            raise CalibrationDirectoryError(
                f"{ident}: std of {result.identified_names[k]!r} is {float(std[k])!r} but the "
                f"covariance's diagonal gives {float(root[k])!r}; {fix}"
            )


def model_files(spec: str) -> dict[str, str]:
    """``{path: SHA-256}`` of the nominal model's files (URDF and sidecar) named by ``spec``.

    Returns:
        An empty map when ``spec`` does not resolve to files (nothing to hash).
    """
    try:
        urdf, side = resolve_model_path(spec)
    except (PincalError, OSError):
        return {}
    out = {}
    for p in (urdf, side):
        if p is not None and Path(p).is_file():
            out[str(Path(p).resolve())] = hash_bounded(Path(p))
    return out


def check_model_files(recorded: object, where: str) -> None:
    """The nominal model's files still have the SHA-256 recorded at calibration time.

    Raises:
        CalibrationDirectoryError: a file changed or is gone (named).
    """
    if recorded is None:
        return
    if not isinstance(recorded, dict):
        raise CalibrationDirectoryError(f"{where}: 'model_files' must map paths to SHA-256")
    for name, digest in recorded.items():
        p = Path(str(name))
        if not p.exists():  # moved: the nominal model is then not found, nothing to compare
            continue
        try:
            now = hash_bounded(p)
        except CalibrationDirectoryError as exc:
            raise CalibrationDirectoryError(
                f"the nominal model file {clip(str(p), 300)} recorded in {where} cannot be read "
                f"({exc}); restore it or re-run `pincal calibrate`"
            ) from None
        if now != digest:
            raise CalibrationDirectoryError(
                f"the nominal model file {clip(str(p), 300)} changed after the calibration was "
                f"written (SHA-256 differs from {where}); the calibration is relative to the "
                "model it was fitted on: restore that file or re-run `pincal calibrate`"
            )


def check_geometry(
    nominal: Mechanism, calibrated: Mechanism, result: IdentificationRecord, urdf: Path
) -> None:
    """``calibrated`` is ``nominal`` displaced by the identified values.

    Skipped when the result's parameters are not those of the model's preset (e.g. an
    instrument calibration that also identifies the instrument).

    Raises:
        CalibrationDirectoryError: a joint origin differs (named, with the offset).
    """
    try:
        expected = result.applied_to(nominal)
    except ParameterError:
        return
    for name, joint in expected.tree.joints.items():
        other = calibrated.tree.joints.get(name)
        if other is None:
            raise CalibrationDirectoryError(
                f"{clip(str(urdf))} has no joint {name!r} of the nominal model; {urdf.name} "
                "and identification.json disagree: re-run `pincal calibrate`"
            )
        diff = float(np.max(np.abs(joint.origin.homogeneous - other.origin.homogeneous)))
        if diff > _ORIGIN_TOL:
            raise CalibrationDirectoryError(
                f"{clip(str(urdf))}: the origin of joint {name!r} is {diff * 1e3:.4g} mm / "
                "mrad away from the nominal model with identification.json's values applied; "
                "the files of the directory disagree: re-run `pincal calibrate`"
            )


def load_json(path: Path) -> dict:
    """A calibration directory's JSON file as a dict (size-capped; refused if not JSON)."""
    text = read_text(path, path.name, _MAX_JSON_BYTES, CalibrationDirectoryError)
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise CalibrationDirectoryError(f"{str(path)!r} is not valid JSON: {exc}") from exc
    except RecursionError:
        raise CalibrationDirectoryError(
            f"{str(path)!r} is nested too deeply to be a pincal file; re-run `pincal calibrate`"
        ) from None
    if not isinstance(data, dict):
        raise CalibrationDirectoryError(f"{str(path)!r} must hold a JSON object")
    return data


def read_noise(entry: object, where: str) -> NoiseModel | None:
    """A stored ``{position_mm, orientation_mrad}`` entry as a NoiseModel (None stays None)."""
    if entry is None:
        return None
    try:
        return NoiseModel(float(entry["position_mm"]), float(entry["orientation_mrad"]))  # type: ignore[index]
    except (TypeError, KeyError, ValueError, PincalError) as exc:
        raise CalibrationDirectoryError(
            f"{where}: 'noise' must be {{position_mm, orientation_mrad}} (positive numbers); "
            f"got {clip(repr(entry))}"
        ) from exc
