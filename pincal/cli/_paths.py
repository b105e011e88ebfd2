"""Output paths on the command line: refuse, before any work, a write over an input.

:func:`guard_paths` (every command calls it with its inputs and outputs),
:func:`overwrite_option` (``--overwrite`` for side files) and :func:`pincal_wrote` (an
implied output pincal wrote may be replaced).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TypeVar

import click

from pincal.errors import InputFileError, OutputPathError, PincalError, clip

__all__ = [
    "PINCAL_CSV_HEADER",
    "WRITTEN_BY",
    "PathLike",
    "guard_paths",
    "overwrite_option",
    "pincal_wrote",
]

_F = TypeVar("_F", bound=Callable[..., object])

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


def _is_calibration_dir(path: Path) -> bool:
    from pincal.io import IDENTIFICATION_FILE, MANIFEST

    return path.is_dir() and any((path / n).exists() for n in (MANIFEST, IDENTIFICATION_FILE))


#: what an implied file pincal wrote begins with (CSV header) or holds (JSON key)
PINCAL_CSV_HEADER = b"# pincal "
WRITTEN_BY = "written_by"


def pincal_wrote(path: Path) -> bool:
    """True when the existing file ``path`` is one pincal wrote (so it may be replaced).

    A CSV file pincal wrote starts with ``# pincal``; a JSON file holds a ``written_by``
    entry starting with ``pincal``.
    """
    import json

    from pincal._files import read_bytes

    try:
        data = read_bytes(path, "file", limit=50_000_000)
    except PincalError:
        return False
    if data.startswith(PINCAL_CSV_HEADER):
        return True
    try:
        doc = json.loads(data)
    except (ValueError, RecursionError):
        return False
    return isinstance(doc, dict) and str(doc.get(WRITTEN_BY, "")).startswith("pincal")


def overwrite_option(func: _F) -> _F:
    """``--overwrite``: replace side files (``<stem>.json``…) pincal did not write."""
    return click.option(
        "--overwrite",
        is_flag=True,
        help="Replace existing side files of --out (e.g. <stem>.json, <stem>.commands.csv, "
        "<stem>.truth.json) even when pincal did not write them.",
    )(func)


def guard_paths(
    inputs: Mapping[str, PathLike],
    outputs: Mapping[str, PathLike] = {},
    out_dirs: Mapping[str, PathLike] = {},
    implied: Mapping[str, PathLike] = {},
    overwrite: bool = False,
) -> None:
    """Refuse, before any work, outputs that would overwrite an input or each other.

    Every command calls this with its inputs and outputs. Paths are compared resolved
    (symbolic links followed, hard links by ``samefile``). An input model directory or
    URDF stands for its URDF and sidecar too, an input calibration directory for its
    files and the nominal model files it records
    (:mod:`pincal.cli._implicit_inputs`). An output directory that is
    replaced as a whole (``calibrate --out``) may not contain an input; no output may lie
    inside an input calibration directory. Outputs must be regular files or absent
    (devices, FIFOs, directories and links to them are refused; a file path ending
    with ``/`` is refused). Implied outputs (side files the user did not name, e.g.
    ``<out>.truth.json``) replace an existing file only when pincal wrote it.

    Args:
        inputs: ``{label: path}`` of the files or directories read (None: not given);
            the label names the option in messages, e.g. ``"--targets"``.
        outputs: ``{label: path}`` of the files written.
        out_dirs: ``{label: path}`` of the directories written (replaced) as a whole.
        implied: ``{label: path}`` of side files written beside an output.
        overwrite: replace existing side files even when pincal did not write them
            (``--overwrite``).

    Raises:
        OutputPathError: naming both paths.
    """
    from pincal.io import output_target

    def resolved(label: str, v: str | os.PathLike) -> Path:
        try:
            return Path(v).resolve()
        except (RuntimeError, OSError):  # Python < 3.13 raises RuntimeError on a loop
            raise InputFileError(
                f"{label} {clip(os.fspath(v), 300)} is a symbolic link loop (links that point "
                "back to each other); give the path of the file itself"
            ) from None

    def given(m: Mapping[str, PathLike]) -> list[tuple[str, Path, str]]:
        return [(k, resolved(k, v), os.fspath(v)) for k, v in m.items() if v is not None]

    from pincal.cli._implicit_inputs import calibration_inputs, model_inputs

    implicit: dict[str, Path] = {}
    for label, v in inputs.items():  # what a model or calibration directory stands for
        if v is not None:
            implicit |= model_inputs(label, v)
            if _is_calibration_dir(Path(v)):
                implicit |= calibration_inputs(v, label)
    ins = given({**inputs, **implicit})
    dirs, sides = given(out_dirs), given(implied)
    outs = given(outputs) + sides
    fix = "inputs are never modified; choose another output path"
    for o_label, _o_path, o_text in outs:
        if o_text.endswith(("/", os.sep)):
            raise OutputPathError(
                f"{o_label} {clip(o_text, 300)} ends with '/', which names a directory; "
                f"give a file name (e.g. {clip(o_text, 200)}out.csv)"
            )
        output_target(o_text, o_label)
    for o_label, o_path, o_text in outs + dirs:
        for i_label, i_path, i_text in ins:
            if _same(o_path, i_path):
                raise OutputPathError(
                    f"{o_label} {clip(o_text, 300)} is the same file as the input {i_label} "
                    f"{clip(i_text, 300)}; {fix}"
                )
            if _inside(o_path, i_path) and _is_calibration_dir(i_path):
                raise OutputPathError(
                    f"{o_label} {clip(o_text, 300)} is inside the input calibration directory "
                    f"{i_label} {clip(i_text, 300)}, whose files are never modified; "
                    "choose an output path outside it"
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
    for s_label, s_path, s_text in sides:
        target = output_target(s_path, s_label)
        if target.exists() and not overwrite and not pincal_wrote(target):
            raise OutputPathError(
                f"{s_label} {clip(s_text, 300)} exists and was not written by pincal; it "
                "would be replaced: move it away, choose another --out, or pass --overwrite"
            )
