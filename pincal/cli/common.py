"""Shared CLI helpers: one-line errors, exit codes, calibration-directory summaries."""

from __future__ import annotations

import os
import sys
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import wraps
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click

from pincal.errors import OutputPathError, PincalError, clip

if TYPE_CHECKING:
    from pincal.io import CalibrationDirectory
    from pincal.model import Mechanism

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


@dataclass(frozen=True)
class ModelOptions:
    """The model-loading options of a command (``--sidecar``, ``--frame``, ``--lock``)."""

    sidecar: str | None = None
    frame: str | None = None
    lock: dict[str, float | str] = field(default_factory=dict)

    @property
    def given(self) -> bool:
        """Whether any option was given."""
        return bool(self.sidecar or self.frame or self.lock)


def _parse_locks(values: tuple[str, ...]) -> dict[str, float | str]:
    out: dict[str, float | str] = {}
    for text in values:
        for item in filter(None, (t.strip() for t in text.split(","))):
            name, eq, value = item.partition("=")
            if eq and name.strip() and value.strip() == "home":
                out[name.strip()] = "home"
                continue
            try:
                number = float(value)
            except ValueError:
                number = float("nan")
            if not eq or not name.strip() or number != number or abs(number) == float("inf"):
                raise click.BadParameter(
                    f"{clip(item, 200)!r}: write JOINT=VALUE [rad or m] or JOINT=home, e.g. "
                    "head_1_joint=0",
                    param_hint="--lock",
                )
            out[name.strip()] = number
    return out


def model_options(func):
    """Add ``--sidecar``, ``--frame`` and ``--lock`` to a command that loads a model.

    The command receives them as one ``model_opts`` (:class:`ModelOptions`) argument.
    """

    @wraps(func)
    def wrapper(*args, sidecar=None, frame=None, lock=(), **kwargs):
        opts = ModelOptions(sidecar, frame, _parse_locks(lock))
        return func(*args, model_opts=opts, **kwargs)

    for decorator in reversed(
        [
            click.option(
                "--sidecar",
                type=click.Path(dir_okay=False),
                default=None,
                help="Sidecar YAML for the model (its keys replace the model's own; "
                "e.g. measured_frame, home, workspace, lock, columns).",
            ),
            click.option(
                "--frame",
                default=None,
                help="Measured frame (a link or frame of the model; wins over the sidecar).",
            ),
            click.option(
                "--lock",
                multiple=True,
                metavar="JOINT=VALUE",
                help="Make a joint fixed at VALUE [rad or m] or at 'home' (repeat, or "
                "comma-separate).",
            ),
        ]
    ):
        wrapper = decorator(wrapper)
    return wrapper


def load_model(spec: str, opts: ModelOptions | None = None, quiet: bool = False) -> Mechanism:
    """Load MODEL with its options; say on stderr when a local path shadows a robot name."""
    from pincal.model import load_mechanism

    opts = opts or ModelOptions()
    mech = load_mechanism(spec, opts.frame, sidecar=opts.sidecar, lock=opts.lock or None)
    if not quiet:
        for note in mech.notes:
            if note.startswith(("model ", "home is a singular", "home (searched)")):
                click.echo(f"pincal: note: {note}", err=True)
    return mech


def model_record(spec: str, opts: ModelOptions) -> str | None:
    """A local sidecar (YAML text) that reloads MODEL with its options, None without options.

    Calibrations write it as ``model.yaml`` so that later commands load the same model.
    """
    if not opts.given:
        return None
    import yaml

    from pincal.model import model_record as record

    return yaml.safe_dump(record(spec, opts.sidecar, opts.frame, opts.lock), sort_keys=False)


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
