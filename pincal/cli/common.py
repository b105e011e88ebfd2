"""Shared CLI helpers: one-line errors, exit codes, calibration-directory summaries."""

from __future__ import annotations

import sys
from functools import wraps
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click

from pincal.errors import PincalError

if TYPE_CHECKING:
    from pincal.io import CalibrationDirectory

EXIT_OK, EXIT_ERROR, EXIT_USAGE = 0, 1, 2


def fail_cleanly(func):
    """Report PincalError (and file/value errors) as one line on stderr, exit code 1.

    With ``pincal --debug`` the exception propagates with its traceback.
    """

    @wraps(func)
    def wrapper(*args, **kwargs):
        ctx = click.get_current_context()
        try:
            return func(*args, **kwargs)
        except (PincalError, OSError, ValueError) as exc:
            root = ctx.find_root().obj or {}
            if root.get("debug"):
                raise
            text = " ".join(str(exc).split())  # errors stay one line
            click.echo(f"pincal: error: {type(exc).__name__}: {text}", err=True)
            sys.exit(EXIT_ERROR)

    return wrapper


def model_source(spec: str) -> str:
    """The model spec to record in a calibration.

    Returns:
        An existing path made absolute, else the name unchanged (a bundled model).
    """
    p = Path(spec)
    return str(p.resolve()) if p.exists() else spec


def calibration_summary(cal: CalibrationDirectory) -> dict[str, Any]:
    """JSON-ready summary of a calibration directory (paths and identity)."""
    return {
        "directory": str(cal.path),
        "model": cal.model,
        "preset": cal.preset,
        "calibrated_urdf": str(cal.calibrated_urdf),
        "legacy": cal.legacy,
    }
