"""`pincal run`: drive a whole calibration campaign from one YAML file.

The campaign is a fixed list of steps (:data:`STEPS`), each the name of an existing
``pincal`` subcommand and a function building its command-line arguments from the
campaign and the paths of the earlier steps' outputs. The steps are invoked in this
process, in order, exactly as a user would type them, so the run writes whatever
the subcommands write. A step whose subcommand this pincal does not have is skipped
with a note; a step that does not apply (no design section, file measurements…)
is skipped silently in the summary.
"""

from __future__ import annotations

import contextlib
import json
import os
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import click

from pincal.cli._campaign import KEYS_HELP, Campaign, load_campaign
from pincal.cli._limits import yes_option
from pincal.cli.common import fail_cleanly


@dataclass(frozen=True)
class Paths:
    """Where the steps read and write (generated inputs in ``<out>-inputs/`` beside ``<out>``)."""

    out: Path
    design: Path
    data: Path
    validation: Path | None
    validation_json: Path


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


def campaign_paths(c: Campaign, out: Path) -> Paths:
    """The step paths of campaign ``c`` writing into ``out``."""
    from pincal.io import VALIDATION_FILE

    inputs = out.parent / f"{out.name}-inputs"  # the calibration directory holds only its own files
    data = Path(c.measurements.file) if c.measurements.file else inputs / "measurements.csv"
    if c.sockets is not None:  # the plain table, imported; absolute: validate --cv reads it
        data = (inputs / "sockets.csv").resolve()
    v = c.validation
    val = None if v.source == "none" else Path(v.file) if v.file else inputs / "validation.csv"
    return Paths(out, inputs / "design.csv", data, val, out / VALIDATION_FILE)


def _writable_ancestor(path: Path) -> Path:
    """The nearest existing ancestor of ``path`` (the directory that gets the new entries)."""
    for parent in path.parents:
        if parent.exists():
            return parent
    return Path(path.anchor or ".")


def check_campaign_outputs(c: Campaign, p: Paths) -> None:
    """Refuse, before the first step, any output location a step would refuse or damage.

    Checks the calibration directory (not the file system root, replaceable: see
    :func:`pincal.io.check_replaceable`), the generated-inputs folder ``<out>-inputs/``,
    every file a step writes there (and its side files) against the campaign's inputs,
    and that the parent directories are writable.

    Raises:
        CampaignError: naming the location and what to change.
    """
    from pincal.cli.common import guard_paths, model_input
    from pincal.errors import CampaignError, PincalError
    from pincal.io import check_replaceable

    out = p.out.resolve()
    if out.parent == out:
        raise CampaignError(
            f"out: {str(p.out)!r} is the file system root; give a directory of its own, "
            "e.g. out: campaign-out (the generated inputs go to OUT-inputs/ beside it)"
        )
    inputs = p.design.parent
    generated = {"design": p.design if c.design else None}
    if c.measurements.file is None or c.sockets is not None:
        generated["measurements"] = p.data
    if c.validation.source == "simulated" and c.validation.file is None:
        generated["validation"] = p.validation
    sides: dict[str, tuple[str, ...]] = {"design": (".commands.csv", ".json")}
    if c.sockets is not None:  # the imported sockets file has no side file
        sides["measurements"] = ()
    implied = {f"the {k} step's {s} file": Path(v).with_suffix(s)
               for k, v in generated.items() if v is not None
               for s in sides.get(k, (".truth.json",))}  # fmt: skip
    try:
        check_replaceable(p.out)
        if inputs.exists() and not inputs.is_dir():
            raise CampaignError(
                f"{str(inputs)!r} (out's inputs folder) exists and is not a directory"
            )
        guard_paths(
            {"model": model_input(c.model), "measurements.file": c.measurements.file,
             "validation.file": c.validation.file},
            {f"{k} file": v for k, v in generated.items()},
            out_dirs={"out": p.out},
            implied=implied,
        )  # fmt: skip
    except PincalError as exc:
        raise CampaignError(f"campaign output: {exc}") from exc
    for where in (out, inputs.resolve()):
        base = _writable_ancestor(where)
        if not os.access(base, os.W_OK | os.X_OK):
            raise CampaignError(
                f"campaign output: cannot create {str(where)!r}: {str(base)!r} is not writable; "
                "choose another out"
            )


def _invoke(ctx: click.Context, step: Step, args: list[str], quiet: bool, yes: bool) -> str:
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


@click.command("run", epilog=KEYS_HELP)
@click.argument("campaign_file", type=click.Path(exists=True, dir_okay=False, path_type=Path))
@click.option("--out", type=click.Path(file_okay=False, path_type=Path), default=None,
              help="Output directory (default: the file's 'out' key).")  # fmt: skip
@click.option("--dry-run", is_flag=True, help="Check the file and print the steps only.")
@click.option("--force", is_flag=True,
              help="calibrate: write even when the quality gate refuses (recorded).")  # fmt: skip
@click.option("--json", "as_json", is_flag=True,
              help="Print a JSON summary on stdout (step output goes to stderr).")  # fmt: skip
@yes_option
@fail_cleanly
@click.pass_context
def run(ctx: click.Context, campaign_file: Path, out: Path | None, dry_run: bool,
        force: bool, as_json: bool, yes: bool) -> None:  # fmt: skip
    """Run the calibration campaign described in CAMPAIGN_FILE (YAML).

    The steps are the pincal subcommands a user would type, in order: poses
    (design) → simulate (calibration and validation data of a seeded "actual"
    machine, or your measurement files) → calibrate → validate → report. Every
    output lands in one calibration directory: the calibrated URDF, identification,
    validation (validation.json) and report files and the resolved campaign in
    campaign.yaml. The report carries what the demo's does: validation, the simulated
    true values and the pose-selection history. The generated inputs
    go to OUT-inputs/ beside it. The whole file is checked before the first step; each step
    prints a progress line on stderr.

    \b
    Examples:
      pincal run docs/examples/campaign.yaml --out cal/
      pincal run campaign.yaml --dry-run       check the file, list the commands
      pincal run campaign.yaml --json          summary as JSON on stdout
    """
    import yaml  # type: ignore[import-untyped]

    from pincal.io import atomic_write_text, calibration_lock

    camp = load_campaign(campaign_file)
    out_dir = Path(out) if out is not None else Path(camp.out)
    paths = campaign_paths(camp, out_dir)
    check_campaign_outputs(camp, paths)
    if not dry_run:  # the whole output, inputs folder included, is this run's until the end
        ctx.with_resource(calibration_lock(paths.out))
        ctx.with_resource(calibration_lock(paths.design.parent))
    summary: dict = {"campaign": str(campaign_file), "out": str(out_dir), "steps": []}
    for k, step in enumerate(STEPS, start=1):
        args = step.arguments(camp, paths)
        tag = f"pincal run: [{k}/{len(STEPS)}] {step.name}"
        record: dict[str, Any] = {"step": step.name, "command": step.command, "args": args}
        summary["steps"].append(record)
        if args is None:
            record["status"] = "not applicable"
            click.echo(f"{tag}: not applicable", err=True)
            continue
        from pincal.cli import main as group

        if group.get_command(ctx, step.command) is None:
            record["status"] = "skipped"
            record["note"] = (
                f"this pincal has no `{step.command}` command; run it later: "
                f"pincal {step.command} {' '.join(args)}"
            )
            click.echo(f"{tag}: skipped — {record['note']}", err=True)
            continue
        click.echo(f"{tag}: pincal {step.command} {' '.join(args)}", err=True)
        if dry_run:
            record["status"] = "planned"
            continue
        t0 = time.perf_counter()
        record["status"] = _invoke(ctx, step, args, as_json, yes)
        record["seconds"] = round(time.perf_counter() - t0, 3)
    if not dry_run:
        # out: "." — the copy lives in the output directory and reruns into it
        dump = yaml.safe_dump({**camp.to_dict(), "out": "."}, sort_keys=False)
        atomic_write_text(out_dir / "campaign.yaml", dump)
        summary["urdf"] = sorted(str(p) for p in out_dir.glob("*.urdf"))
        summary["report"] = sorted(str(p) for p in out_dir.glob("report.*"))
    if as_json:
        click.echo(json.dumps(summary))
    else:
        done = sum(s["status"] == "done" for s in summary["steps"])
        click.echo(f"campaign {'checked' if dry_run else 'done'}: {done} steps run; {out_dir}")
