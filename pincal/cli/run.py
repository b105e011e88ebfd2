"""`pincal run`: drive a whole calibration campaign from one YAML file.

The campaign is a fixed list of steps (:data:`pincal.cli._campaign_steps.STEPS`), each
the name of an existing ``pincal`` subcommand and a function building its command-line
arguments from the campaign and the paths of the earlier steps' outputs
(:mod:`pincal.cli._campaign_paths`). The steps are invoked in this
process, in order, exactly as a user would type them, so the run writes whatever
the subcommands write. A step whose subcommand this pincal does not have is skipped
with a note; a step that does not apply (no design section, file measurements…)
is skipped silently in the summary.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import click

from pincal.cli._campaign import KEYS_HELP, load_campaign
from pincal.cli._limits import yes_option
from pincal.cli.common import fail_cleanly


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

    from pincal.cli import main as group
    from pincal.cli._campaign_paths import campaign_paths, check_campaign_outputs
    from pincal.cli._campaign_steps import STEPS, invoke_step
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
        record["status"] = invoke_step(ctx, step, args, as_json, yes)
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
