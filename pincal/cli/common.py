"""Shared CLI helpers: one-line errors, exit codes, calibration-directory summaries."""

from __future__ import annotations

import os
import sys
from collections.abc import Mapping
from functools import wraps
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click

from pincal.errors import OutputPathError, PincalError, clip

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


def model_input(spec: str) -> str | None:
    """The model spec as an input path for :func:`guard_paths` (None for a bundled name)."""
    return spec if Path(spec).exists() else None


def calibration_summary(cal: CalibrationDirectory) -> dict[str, Any]:
    """JSON-ready summary of a calibration directory (paths and identity)."""
    return {
        "directory": str(cal.path),
        "model": cal.model,
        "preset": cal.preset,
        "calibrated_urdf": str(cal.calibrated_urdf),
        "legacy": cal.legacy,
    }


PathLike = str | os.PathLike | None


def _same(a: Path, b: Path) -> bool:
    if a == b:
        return True
    try:
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except OSError:
        return False


def _inside(path: Path, directory: Path) -> bool:
    return path != directory and path.is_relative_to(directory)


def guard_paths(
    inputs: Mapping[str, PathLike],
    outputs: Mapping[str, PathLike] = {},
    out_dirs: Mapping[str, PathLike] = {},
) -> None:
    """Refuse, before any work, outputs that would overwrite an input or each other.

    Every command calls this with its inputs and outputs. Paths are compared resolved
    (symbolic links followed, hard links by ``samefile``). An output directory that is
    replaced as a whole (``calibrate --out``) may not contain an input.

    Args:
        inputs: ``{label: path}`` of the files or directories read (None: not given);
            the label names the option in messages, e.g. ``"--targets"``.
        outputs: ``{label: path}`` of the files written.
        out_dirs: ``{label: path}`` of the directories written (replaced) as a whole.

    Raises:
        OutputPathError: naming both paths.
    """

    def given(m: Mapping[str, PathLike]) -> list[tuple[str, Path, str]]:
        return [(k, Path(v).resolve(), os.fspath(v)) for k, v in m.items() if v is not None]

    ins, outs, dirs = given(inputs), given(outputs), given(out_dirs)
    fix = "inputs are never modified; choose another output path"
    for o_label, o_path, o_text in outs + dirs:
        for i_label, i_path, i_text in ins:
            if _same(o_path, i_path):
                raise OutputPathError(
                    f"{o_label} {clip(o_text, 300)} is the same file as the input {i_label} "
                    f"{clip(i_text, 300)}; {fix}"
                )
    for d_label, d_path, d_text in dirs:
        for i_label, i_path, i_text in ins:
            if _inside(i_path, d_path):
                raise OutputPathError(
                    f"the input {i_label} {clip(i_text, 300)} is inside the output directory "
                    f"{d_label} {clip(d_text, 300)}, which is replaced as a whole; {fix}"
                )
    for k, (a_label, a_path, a_text) in enumerate(outs):
        for b_label, b_path, b_text in outs[k + 1 :]:
            if _same(a_path, b_path):
                raise OutputPathError(
                    f"{a_label} {clip(a_text, 300)} and {b_label} {clip(b_text, 300)} are the same "
                    f"file (the command writes both); give output paths that differ"
                )
