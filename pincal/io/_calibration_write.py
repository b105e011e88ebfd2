"""Writing the calibration directory whole or not at all (:func:`write_calibration`).

:func:`write_calibration` writes the whole directory (see :mod:`pincal.io._calibration_dir`
for its files) into a temporary sibling (``.NAME.pincal-tmp-*``) and swaps it in with one
rename, so the directory is at every instant the complete old set or the complete new
one; a lock file beside it (``.NAME.pincal-lock``) keeps a second writer out.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from collections.abc import Mapping, Sequence
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import yaml  # type: ignore[import-untyped]

from pincal._version import __version__
from pincal.errors import UnidentifiableError, clip
from pincal.identification import IdentificationRecord, IdentificationResult, result_to_dict
from pincal.io._atomic import (
    atomic_write_text,
    calibration_lock,
    remove_stale_temporaries,
    swap_in_directory,
    temp_prefix,
)
from pincal.io._calibration_checks import model_files
from pincal.io._calibration_dir import CALIBRATION_VERSION, CalibrationDirectory, read_calibration
from pincal.io._calibration_replace import check_resolved_replaceable
from pincal.io._digest import sha256_file
from pincal.io._file_names import (
    CALIBRATED_SIDECAR,
    CALIBRATED_URDF,
    CALIBRATION_FORMAT,
    IDENTIFICATION_FILE,
    MANIFEST,
    MODEL_RECORD,
    NOMINAL_URDF,
)
from pincal.io._urdf_export import save_urdf
from pincal.measure import NoiseModel
from pincal.model import Mechanism

__all__ = ["sha256_file", "write_calibration"]


def _model_entries(model_source: str | None, out: Path, record: str | None) -> dict[str, Any]:
    """The manifest's model entries: source, the model's files hashed, its relative path.

    A calibration with a model record (``model.yaml``, its options) names it relative to
    the directory; the model it reloads (its ``robot``) is what is hashed. A model kept
    at a local path is also recorded relative to the directory (``model_relative``), so
    a project moved whole finds it from anywhere (checked against the hashes).
    """
    robot = model_source
    if model_source == MODEL_RECORD:
        doc = yaml.safe_load(record or "") or {}
        robot = str(doc.get("robot") or "") if isinstance(doc, dict) else ""
    entries: dict[str, Any] = {
        "model_source": model_source,
        "model_files": model_files(robot) if robot else {},
    }
    if robot and Path(robot).is_absolute():
        entries["model_relative"] = os.path.relpath(robot, out)
    return entries


def _data_entry(p: str | Path, out: Path) -> dict[str, str]:
    """A fitted data file: as typed, absolute, relative to the directory, SHA-256."""
    absolute = Path(p).resolve()
    return {"path": str(p), "absolute_path": str(absolute),
            "relative_path": os.path.relpath(absolute, out), "name": Path(p).name,
            "sha256": sha256_file(p)}  # fmt: skip


def _manifest(
    result: IdentificationRecord,
    model_source: str | None,
    data_files: Sequence[str | Path],
    noise: NoiseModel | None,
    files: dict[str, str],
    out: Path,
    record: str | None = None,
) -> dict[str, Any]:
    ident = result.identified
    return {
        "format": CALIBRATION_FORMAT,
        "version": CALIBRATION_VERSION,
        "pincal_version": __version__,
        "created": datetime.now(UTC).isoformat(timespec="seconds"),
        "model": result.model,
        **_model_entries(model_source, out, record),
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
        "data_files": [_data_entry(p, out) for p in data_files],
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
        model_source: the nominal model spec (bundled name or absolute path) for later
            commands, or ``"model.yaml"`` when ``texts`` holds that model record.
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
    """
    _check_placed(result)
    out = Path(path).resolve()  # "." or "cal/" name a directory we can replace by rename
    out.parent.mkdir(parents=True, exist_ok=True)
    with calibration_lock(out):
        _write_locked(out, result, model_source, data_files, noise, annotations, texts, nominal)
    return read_calibration(out)  # resolved: "." names the old directory after the swap


def _check_placed(result: IdentificationResult) -> None:
    """Refuse, before anything is written, a fit that placed no parameter.

    Its directory would have no parameter: its own reader refuses it.

    Raises:
        UnidentifiableError: no parameter identified (the gauge's reason named).
    """
    if len(result.identified_names):
        return
    weak = [g for g in (result.joint.gauge if result.joint else ()) if "too weakly" in g]
    if weak:  # our own text: "seen too weakly to place within …, held at nominal: names"
        why = f": {weak[0].split(', held at nominal')[0][:120]}"
        fix = ("the declared σ is too large for the data to place any (check the data "
               "file's '# std:' or '# noise:' header and its unit), or measure more poses")
    else:
        why = ""
        fix = "the data do not see the parameters: check the measured frame and --params"
    raise UnidentifiableError(
        f"the fit placed no parameter of {clip(result.model)} (all {len(result.names)} held "
        f"at nominal{why}); nothing was written: {fix}",
        result.names,
    )


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
    check_resolved_replaceable(out)
    remove_stale_temporaries(out)
    mech = result.calibrated
    notes = {"data": [str(p) for p in data_files], "calibrated_urdf": CALIBRATED_URDF}
    notes.update(annotations or {})
    tmp = Path(tempfile.mkdtemp(prefix=temp_prefix(out, "tmp"), dir=out.parent))
    try:
        save_urdf(mech, tmp / CALIBRATED_URDF)
        doc = result_to_dict(result, notes)
        atomic_write_text(tmp / IDENTIFICATION_FILE, json.dumps(doc, indent=1) + "\n")
        for name, text in (texts or {}).items():
            atomic_write_text(tmp / name, text)
        if nominal is not None:
            save_urdf(nominal, tmp / NOMINAL_URDF)
        files = {p.name: sha256_file(p) for p in sorted(tmp.iterdir()) if p.is_file()}
        record = (texts or {}).get(MODEL_RECORD)
        manifest = _manifest(result, model_source, data_files, noise, files, out, record)
        if annotations and "quality" in annotations:  # the quality gate's verdict / override
            manifest["quality"] = annotations["quality"]
        if nominal is not None:
            manifest["nominal_urdf"] = NOMINAL_URDF
            manifest["markers"] = (annotations or {}).get("markers")
        atomic_write_text(tmp / MANIFEST, json.dumps(manifest, indent=1) + "\n")
        os.chmod(tmp, 0o755)
        read_calibration(tmp)  # read back before it replaces anything: never a directory
        check_resolved_replaceable(out)  # its own reader refuses in place of a good one
        swap_in_directory(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


