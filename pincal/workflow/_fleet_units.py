"""The units of a fleet run as ``pincal fleet run`` hands them out and reads them back.

:func:`fleet_jobs` lists one executor item per unit of a fleet file (and the key its
result is stored under, which changes with the unit's data); :func:`unit_summary`
reads a unit's complete calibration directory into the small summary the fleet test
needs (its identified values and covariance). The calibration itself is the
``calibrate`` command's, run by the command line in a worker.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from pincal.errors import PincalError
from pincal.io import Fleet, read_calibration, sha256_file

__all__ = ["UnitJob", "file_digest", "fleet_jobs", "unit_summary"]

#: one unit's work: (model, preset or None, unit label (id, or id@date for one of several
#: sessions), data file, calibration directory, method, log file), every path absolute
UnitJob = tuple[str, str | None, str, str, str, str, str]


def file_digest(path: str | Path) -> str:
    """SHA-256 (hex) of a file's bytes, read as every input is (:func:`pincal.io.sha256_file`).

    Raises:
        CalibrationDirectoryError: not a regular file, or unreadable.
        InputLimitError: larger than the input size cap (a sparse 50 GB file is refused
            at once, never hashed for minutes).
    """
    return sha256_file(path)


def fleet_jobs(fleet: Fleet, root: Path, method: str) -> tuple[list[UnitJob], list[str]]:
    """One :data:`UnitJob` per unit of ``fleet`` and its result's key.

    Args:
        fleet: the fleet file as read.
        root: the report directory (absolute): units go to ``root/units/<label>``, their
            logs to ``root/logs/<label>.log`` (the label: the id, or ``<id>@<date>`` for
            one of a unit's several sessions).
        method: the identification method of every unit.

    Returns:
        The jobs (N,) and keys (N,) ``<label>.<first 16 hex digits of the data's SHA-256>``.
    """
    jobs: list[UnitJob] = [
        (fleet.model, fleet.preset, u.label, str(u.data.resolve()),
         str(root / "units" / u.label), method, str(root / "logs" / f"{u.label}.log"))
        for u in fleet.units
    ]  # fmt: skip
    keys = [f"{u.label}.{file_digest(u.data)[:16]}" for u in fleet.units]
    return jobs, keys


def unit_summary(
    uid: str, out: str | Path, data: str | Path | None = None
) -> dict[str, Any] | None:
    """The summary of a complete calibration directory, or None when it is not one.

    Args:
        uid: the unit's id.
        out: its calibration directory.
        data: its data file: the directory counts as complete only when it was
            calibrated from this file's current content.

    Returns:
        ``{id, status: "calibrated", names (k,), units (k,), values (k,) [m, rad],
        covariance (k, k) [SI], gate_passed, rms_after_mm}``, or None.
    """
    if not (Path(out) / "calibration.json").is_file():
        return None
    try:
        cal = read_calibration(out)
    except PincalError:
        return None
    if data is not None:
        files = cal.manifest.get("data_files") or [{}]
        if files[0].get("sha256") != file_digest(data):
            return None
    r = cal.result
    mask = np.asarray(r.identified, dtype=bool)
    quality = cal.manifest.get("quality") or {}
    after = r.after.rms_position if r.after is not None else None
    return {
        "id": uid,
        "status": "calibrated",
        "names": [n for n, m in zip(r.names, mask, strict=True) if m],
        "units": [u for u, m in zip(r.units, mask, strict=True) if m],
        "values": [float(v) for v in np.asarray(r.full_values, dtype=float)[mask]],
        "covariance": np.asarray(r.covariance, dtype=float).tolist(),
        "gate_passed": bool(quality.get("passed", True)),
        "rms_after_mm": None if after is None else 1e3 * float(after),
    }
