"""The files a command reads without naming them: a model's URDF and sidecar, a calibration's.

:func:`pincal.cli._paths.guard_paths` compares outputs with inputs; an input named on
the command line often stands for more files: a model directory for its URDF and
sidecar, a calibration directory for its own files, the nominal model it was fitted on
(``model_files`` of its manifest) and, for ``validate --cv``, the data file it was
fitted on. Those are inputs too: an output that is one of them is refused before any
work (``validate --out models/arm/arm.urdf`` would overwrite the nominal model the
calibration loads; ``validate --cv --folds-out m.csv`` the file the folds are read
from).
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["calibration_inputs", "model_inputs"]


def model_inputs(label: str, spec: str | os.PathLike) -> dict[str, Path]:
    """The URDF and sidecar a model path stands for (``{}`` for anything else).

    Args:
        label: what names the input in messages (e.g. ``"MODEL"``).
        spec: an existing model directory or ``.urdf`` file; a bundled name, a data
            file or a missing path give ``{}``.

    Returns:
        ``{"<label>'s URDF" / "<label>'s sidecar": path}`` of the files loading it reads
        (the spec itself left out).
    """
    from pincal.errors import PincalError
    from pincal.model import resolve_model_path

    p = Path(spec)
    if not (p.is_dir() or (p.is_file() and p.suffix.lower() == ".urdf")):
        return {}
    try:
        urdf, side = resolve_model_path(p)
    except (PincalError, OSError):
        return {}
    files = [f for f in (urdf, side) if f is not None and f.is_file() and f != p]
    return {f"{label}'s {'URDF' if f == urdf else 'sidecar'}": f for f in files}


def calibration_inputs(
    directory: str | os.PathLike, label: str = "CALIBRATION", data_files: bool = False
) -> dict[str, Path]:
    """The files a command using calibration ``directory`` reads.

    Its manifest, identification record, calibrated URDF and sidecar and every file its
    manifest hashes; the nominal model's files it records (``model_files``, those that
    exist); with ``data_files`` the data files it was fitted on, found by their SHA-256
    as ``validate --cv`` finds them (a file not found is not an input).

    Args:
        directory: the calibration directory (``{}`` when it holds no manifest).
        label: what names it in messages.
        data_files: also the recorded data files.

    Returns:
        ``{"<label>'s <what>": path}`` (file name, nominal model, data file).
    """
    from pincal.errors import PincalError
    from pincal.io import (
        CALIBRATED_SIDECAR,
        CALIBRATED_URDF,
        IDENTIFICATION_FILE,
        MANIFEST,
        read_calibration,
    )

    d = Path(directory)
    names = {MANIFEST, IDENTIFICATION_FILE, CALIBRATED_URDF, CALIBRATED_SIDECAR}
    out = {f"{label}'s {n}": d / n for n in sorted(names) if (d / n).exists()}
    if not (d / MANIFEST).is_file():
        return out
    try:
        cal = read_calibration(d, verify=False)
    except PincalError:
        return out  # the command itself names what is wrong with it
    for n in sorted(set(cal.manifest.get("files") or {}) | {cal.calibrated_urdf.name}):
        if (d / n).exists():
            out[f"{label}'s {n}"] = d / n
    for f in cal.model_paths():  # where they are now (a project moved whole: beside it)
        kind = "nominal model" if f.suffix.lower() == ".urdf" else "nominal model's sidecar"
        out[f"{label}'s {kind}"] = f
    if data_files:
        for k in range(len(cal.manifest.get("data_files") or [])):
            try:
                f = cal.data_file(k)
            except PincalError:
                continue
            out[f"{label}'s data file" + (f" {k + 1}" if k else "")] = f
    return out
