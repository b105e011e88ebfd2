"""The steps of ``pincal run``: each an existing ``pincal`` subcommand and its arguments.

The campaign is a fixed list of steps (:data:`STEPS`), each the name of a subcommand
and a function building its command-line arguments from the campaign and the paths
of the earlier steps' outputs (:class:`pincal.cli._campaign_paths.Paths`); None when
the step does not apply. :func:`invoke_step` runs one in this process, exactly as a
user would type it.
"""

from __future__ import annotations

import contextlib
import sys
from collections.abc import Callable
from dataclasses import dataclass

import click

from pincal.cli._campaign import Campaign
from pincal.cli._campaign_paths import Paths

__all__ = ["STEPS", "Step", "invoke_step"]


@dataclass(frozen=True)
class Step:
    """One campaign step: a subcommand and its argument builder (None = not applicable)."""

    name: str
    command: str
    arguments: Callable[[Campaign, Paths], list[str] | None]


def _pair(v: tuple[float, float]) -> str:
    return f"{v[0]!r},{v[1]!r}"


def _actual(c: Campaign) -> list[str]:
    m = c.measurements
    opts = ["--errors", f"seed:{m.errors_seed}", "--error-size", _pair(m.error_size)]
    opts += ["--noise", _pair(m.noise)]
    return opts + (["--params", c.preset] if c.preset else [])


def _design(c: Campaign, p: Paths) -> list[str] | None:
    d = c.design
    if d is None:
        return None
    args = [c.model, "--count", str(d.count), "--index", d.index, "--candidates", d.candidates]
    args += ["--method", d.method, "--seed", str(d.seed), "--out", str(p.design)]
    return args + (["--preset", c.preset] if c.preset else [])


def _measure(c: Campaign, p: Paths) -> list[str] | None:
    m = c.measurements
    if m.source != "simulated":
        return None
    where = ["--poses", str(p.design)] if c.design else ["--random", str(m.poses)]
    return [c.model, *where, *_actual(c), "--seed", str(m.seed), "--out", str(p.data)]


def _measure_validation(c: Campaign, p: Paths) -> list[str] | None:
    v = c.validation
    if v.source != "simulated" or p.validation is None:
        return None
    return [c.model, "--random", str(v.poses), *_actual(c), "--seed", str(v.seed),
            "--out", str(p.validation)]  # fmt: skip


def _import_sockets(c: Campaign, p: Paths) -> list[str] | None:
    """A plain CSV of socket seatings → the sockets file the calibration reads."""
    if c.sockets is None or c.measurements.file is None:
        return None
    return [c.measurements.file, "--model", c.model, *c.sockets.options(), "--out", str(p.data)]


def _calibrate(c: Campaign, p: Paths) -> list[str] | None:
    i = c.identification
    args = [c.model, "--data", str(p.data), "--method", i.method]
    if c.markers is not None:
        args += c.markers.options()
        args += ["--prior", i.prior] if i.prior else []
    args += ["--loss", i.loss] if i.loss is not None else []
    args += ["--model", i.model] if i.model != "geometric" else []
    ctx = click.get_current_context(silent=True)  # `pincal run --force` passes it on
    args += ["--force"] if ctx is not None and ctx.params.get("force") else []
    inst = c.identification.instrument
    args += ["--instrument", inst] if inst is not None else []
    args += ["--bootstrap", str(i.bootstrap)] if i.bootstrap else []
    return args + (["--params", c.preset] if c.preset else []) + ["--out", str(p.out)]


def _validate(c: Campaign, p: Paths) -> list[str] | None:
    v = c.validation
    args = [] if p.validation is None else ["--data", str(p.validation)]
    if v.cv is not None:
        folds = p.out.parent / f"{p.out.name}-inputs" / "cv_folds.csv"
        args += ["--cv", str(v.cv), "--seed", str(v.cv_seed), "--folds-out", str(folds)]
    return [str(p.out), *args, "--out", str(p.validation_json)] if args else None


def _report(c: Campaign, p: Paths) -> list[str] | None:
    """The report, with what the other steps wrote: validation, truth, pose design."""
    if not c.report:
        return None
    args = [str(p.out)]
    if p.validation is not None or c.validation.cv is not None:  # what the validate step wrote
        args += ["--validation", str(p.validation_json)]
    if c.measurements.source == "simulated":
        args += ["--truth", str(p.data.with_suffix(".truth.json"))]
    if c.design is not None:
        args += ["--design", str(p.design.with_suffix(".json"))]
    return args


#: the campaign, in order: (step name, pincal subcommand, argument builder)
STEPS: tuple[Step, ...] = (
    Step("design", "poses", _design),
    Step("measure", "simulate", _measure),
    Step("measure-validation", "simulate", _measure_validation),
    Step("import-sockets", "import-sockets", _import_sockets),
    Step("calibrate", "calibrate", _calibrate),
    Step("validate", "validate", _validate),
    Step("report", "report", _report),
)


def invoke_step(ctx: click.Context, step: Step, args: list[str], quiet: bool, yes: bool) -> str:
    """Run one step; returns its status (``done`` or ``skipped``).

    With ``yes``, steps whose command has ``--yes`` get it (past the size bounds).
    """
    from pincal.cli import main as group
    from pincal.errors import CampaignError

    cmd = group.get_command(ctx, step.command)
    if cmd is None:
        return "skipped"
    if yes and any(p.name == "yes" for p in cmd.params):
        args = [*args, "--yes"]
    try:
        sub = cmd.make_context(step.command, list(args), parent=ctx)
    except click.ClickException as exc:
        raise CampaignError(
            f"step {step.name!r}: `pincal {step.command}` rejected the arguments "
            f"{args}: {exc.format_message()}"
        ) from exc
    out = contextlib.redirect_stdout(sys.stderr) if quiet else contextlib.nullcontext()
    try:
        with sub, out:
            cmd.invoke(sub)
    except click.ClickException as exc:
        raise CampaignError(
            f"step {step.name!r} (`pincal {step.command}`): {exc.format_message()}"
        ) from exc
    except SystemExit as exc:
        if exc.code:  # the step printed its error on stderr
            raise CampaignError(
                f"step {step.name!r} failed (`pincal {step.command}`, its error is above); "
                "the run stops here"
            ) from None
        raise
    return "done"
