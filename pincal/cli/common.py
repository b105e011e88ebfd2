"""Shared CLI helpers: one-line errors, exit codes, calibration-directory summaries."""

from __future__ import annotations

import os
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import wraps
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn, ParamSpec, TypeVar

import click

from pincal.errors import PincalError, clip

if TYPE_CHECKING:
    from click.decorators import FC

    from pincal.io import CalibrationDirectory
    from pincal.model import Mechanism

EXIT_OK, EXIT_ERROR, EXIT_USAGE = 0, 1, 2

_P = ParamSpec("_P")
_R = TypeVar("_R")


def _wants_json(ctx: click.Context) -> bool:
    return bool(ctx.params.get("as_json"))


def _json_error(exc: BaseException, message: str) -> None:
    import json

    doc = {"error": {"type": type(exc).__name__, "message": message}}
    click.echo(json.dumps(doc, ensure_ascii=False))


def _pipe_closed() -> NoReturn:
    """The reader of stdout went away (``| head``): stop quietly, exit 0 (Unix convention)."""
    try:  # further writes (and the flush at exit) go nowhere instead of raising again
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):
        pass
    sys.exit(EXIT_OK)


def fail_cleanly(func: Callable[_P, _R]) -> Callable[_P, _R]:
    """Report PincalError (and file/value errors) as one line on stderr, exit code 1.

    With ``--json`` (the command's ``as_json``) the error is instead one JSON object on
    stdout, ``{"error": {"type": …, "message": …}}``, with the same exit code (2 for
    command-line usage errors). A closed stdout (``pincal … | head``) ends the command
    silently with exit 0. With ``pincal --debug`` the exception propagates with its
    traceback.
    """

    @wraps(func)
    def wrapper(*args: _P.args, **kwargs: _P.kwargs) -> _R:
        ctx = click.get_current_context()
        try:
            _apply_environment(ctx)
            out = func(*args, **kwargs)
            sys.stdout.flush()  # a closed pipe is reported here, not at interpreter exit
            return out
        except BrokenPipeError:
            _pipe_closed()
        except click.ClickException as exc:
            if not _wants_json(ctx) or (ctx.find_root().obj or {}).get("debug"):
                raise
            _json_error(exc, " ".join(exc.format_message().split()))
            sys.exit(exc.exit_code)
        except (PincalError, OSError, ValueError, RecursionError) as exc:
            root = ctx.find_root().obj or {}
            if root.get("debug"):
                raise
            text = " ".join(str(exc).split())  # errors stay one line
            if isinstance(exc, RecursionError):
                text = (
                    "an input is nested too deeply to read (JSON, YAML or XML thousands of "
                    "levels deep); pincal's files are shallow: check the file given"
                )
            if _wants_json(ctx):
                _json_error(exc, text)
            else:
                click.echo(f"pincal: error: {type(exc).__name__}: {text}", err=True)
            sys.exit(EXIT_ERROR)

    return wrapper


def _apply_environment(ctx: click.Context) -> None:
    """Read the ``PINCAL_MAX_*`` limits once per invocation and run the command under them.

    Raises:
        InputLimitError: a variable is malformed.
    """
    from pincal.cli._environment import limits_from_environment

    root = ctx.find_root()
    root.ensure_object(dict)
    if "limits" not in root.obj:
        root.obj["limits"] = limits_from_environment(os.environ)
        root.with_resource(root.obj["limits"].applied())


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


def jobs_option(help_text: str) -> Callable[[FC], FC]:
    """``--jobs N`` (into ``n_jobs``): worker processes, -1 for every CPU, default 1."""
    return click.option("--jobs", "n_jobs", type=click.IntRange(min=-1), default=1,
                        show_default=True, help=help_text)  # fmt: skip


def scheduler_option(what: str) -> Callable[[FC], FC]:
    """``--scheduler`` (into ``scheduler``): run ``what`` on dask.distributed."""
    return click.option(
        "--scheduler", default=None, metavar="local:N|tcp://HOST:PORT",
        help=f"Run {what} on dask.distributed: local:N (a local cluster of N worker "
        "processes) or a scheduler address tcp://host:8786 (its workers must see the same "
        'file paths). Needs the optional extra: pip install "pincal[dask]". Default: local '
        "processes (--jobs).",
    )  # fmt: skip


def model_options(func: Callable[..., _R]) -> Callable[..., _R]:
    """Add ``--sidecar``, ``--frame`` and ``--lock`` to a command that loads a model.

    The command receives them as one ``model_opts`` (:class:`ModelOptions`) argument.
    """

    @wraps(func)
    def wrapper(
        *args: object,
        sidecar: str | None = None,
        frame: str | None = None,
        lock: tuple[str, ...] = (),
        **kwargs: object,
    ) -> _R:
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


def announce(cal: CalibrationDirectory) -> None:
    """Print the calibration's caveat (forced past the gate, failed solve) on stderr."""
    if cal.caveat:
        click.echo(f"pincal: warning: {cal.caveat}", err=True)


def calibration_summary(cal: CalibrationDirectory) -> dict[str, Any]:
    """JSON-ready summary of a calibration directory (paths and identity)."""
    return {
        "directory": str(cal.path),
        "model": cal.model,
        "preset": cal.preset,
        "calibrated_urdf": str(cal.calibrated_urdf),
    }
