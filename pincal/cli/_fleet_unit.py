"""One unit of a fleet: calibrated by `pincal calibrate` itself, in a worker process.

:func:`calibrate_unit` runs the ``calibrate`` command in-process (the same checks,
gate and calibration directory as on the command line), keeps its output in a log
file, and returns a small summary the fleet test reads: the identified values and
their covariance, or why the gate refused the unit. A unit whose calibration directory
is complete (readable, its data file unchanged) is read back, not calibrated again.
"""

from __future__ import annotations

import contextlib
import io
import json
from typing import Any

from pincal.errors import ItemFailedError

__all__ = ["calibrate_unit"]


def calibrate_unit(item: tuple[str, str | None, str, str, str, str, str]) -> dict[str, Any]:
    """Calibrate one unit (an executor item; workers import this function).

    Args:
        item: ``(model, preset or None, unit id, data file, calibration directory,
            method, log file)``.

    Returns:
        The unit's :func:`pincal.workflow.unit_summary` (``reused`` True when it was
        read back), or
        ``{id, status: "refused", reason}`` when the quality gate refused it.

    Raises:
        ItemFailedError: any other error of the calibration (named, with its message).
    """
    from pincal.cli.calibrate import calibrate
    from pincal.workflow import unit_summary

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
