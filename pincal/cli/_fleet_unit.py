"""One unit of a fleet: calibrated by `pincal calibrate` itself, in a worker process.

:func:`calibrate_unit` runs the ``calibrate`` command in-process (the same checks,
gate and calibration directory as on the command line), keeps its output in a log
file, and returns a small summary the fleet test reads: the identified values and
their covariance, or why the gate refused the unit. A unit whose calibration directory
is complete (readable, its data file unchanged) is read back, not calibrated again.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
from pathlib import Path
from typing import Any

from pincal.errors import ItemFailedError

__all__ = ["calibrate_unit", "file_digest", "unit_summary"]


def file_digest(path: str | Path) -> str:
    """SHA-256 (hex) of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def unit_summary(uid: str, out: str | Path, data: str | Path | None = None) -> dict | None:
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
    import numpy as np

    from pincal.errors import PincalError
    from pincal.io import read_calibration

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


def calibrate_unit(item: tuple[str, str | None, str, str, str, str, str]) -> dict[str, Any]:
    """Calibrate one unit (an executor item; workers import this function).

    Args:
        item: ``(model, preset or None, unit id, data file, calibration directory,
            method, log file)``.

    Returns:
        The unit's :func:`unit_summary` (``reused`` True when it was read back), or
        ``{id, status: "refused", reason}`` when the quality gate refused it.

    Raises:
        ItemFailedError: any other error of the calibration (named, with its message).
    """
    from pincal.cli.calibrate import calibrate

    model, preset, uid, data, out, method, log = item
    done = unit_summary(uid, out, data)
    if done is not None:
        return done | {"reused": True}
    args = [model, "--data", data, "--out", out, "--method", method, "--json"]
    args += ["--params", preset] if preset else []
    stdout, stderr = io.StringIO(), io.StringIO()
    code: Any = 0
    with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
        try:
            calibrate.main(args, prog_name="pincal calibrate", standalone_mode=False, obj={})
        except SystemExit as exc:
            code = exc.code
    from pincal.io import atomic_write_text

    atomic_write_text(  # creates the unit's directory when missing
        log, f"$ pincal calibrate {' '.join(args)}\n{stderr.getvalue()}{stdout.getvalue()}"
    )
    if code in (0, None):
        summary = unit_summary(uid, out)
        if summary is None:
            raise ItemFailedError(
                f"unit {uid}: calibrate wrote no readable directory {out}", uid, ""
            )
        return summary | {"reused": False}
    try:
        error = json.loads(stdout.getvalue().strip().splitlines()[-1])["error"]
    except (ValueError, KeyError, IndexError, TypeError):
        error = {"type": "Error", "message": stderr.getvalue().strip()[-500:] or f"exit {code}"}
    if error.get("type") == "QualityGateError":
        return {"id": uid, "status": "refused", "reason": str(error.get("message"))}
    raise ItemFailedError(
        f"unit {uid}: {error.get('type')}: {error.get('message')}", uid, str(error.get("type"))
    )
