"""`pincal demo`: the main job."""

from __future__ import annotations

import click

from pincal.cli._limits import MAX_POSES, check_count, naming_option, yes_option
from pincal.cli.common import fail_cleanly


@click.command()
@click.option("--seed", default=7, type=click.IntRange(min=0), show_default=True,
              help="Random seed of the simulation.")  # fmt: skip
@click.option("--poses", default=30, show_default=True, help="Number of measurement poses.")
@click.option("--validation", default=60, show_default=True, help="Fresh validation poses.")
@click.option(
    "--method",
    type=click.Choice(["gauss-newton", "lm"]),
    default="gauss-newton",
    show_default=True,
)
@click.option(
    "--candidates",
    default="auto",
    show_default=True,
    help="Candidate poses for O1 selection (auto, grid:LEVELS, random:N, oa:P) or 'none' for "
    "random.",
)
@click.option("--out", default="pincal-out", show_default=True, help="Output directory.")
@click.option("--report/--no-report", default=True, show_default=True, help="Write report.html.")
@click.option("--json", "as_json", is_flag=True, help="Print a JSON summary on stdout.")
@yes_option
@click.option(
    "--force", is_flag=True, help="Write the calibration even if the quality gate refuses it."
)
@fail_cleanly
def demo(
    seed: int,
    poses: int,
    validation: int,
    method: str,
    candidates: str,
    out: str,
    report: bool,
    as_json: bool,
    yes: bool,
    force: bool,
) -> None:
    """Simulated calibration of the bundled 6-UPS Stewart platform (42 parameters).

    Draws an "actual" machine (0.5 mm errors), simulates a laser-tracker campaign
    (pincal's default noise, 0.01 mm / 0.02 mrad), identifies the parameters, validates
    on fresh poses and writes the calibration directory OUT (calibration.json, calibrated.urdf +
    calibrated.yaml, identification.json) with report.html.

    \b
    Examples:
      pincal demo
      pincal demo --seed 3 --poses 18 --method lm --out run3
      pincal demo --no-report --json
    """
    from pincal.cli._demo_job import (
        collections_skip_the_imports,
        demo_summary,
        format_demo,
        run_demo,
    )
    from pincal.design import parse_candidate_spec
    from pincal.workflow import DemoSettings

    check_count(poses, "--poses", MAX_POSES, yes)
    check_count(validation, "--validation", MAX_POSES, yes)
    if candidates != "none":
        with naming_option("--candidates"):
            parse_candidate_spec(candidates)
    settings = DemoSettings(seed=seed, n_poses=poses, n_validation=validation, method=method,
                            candidates=candidates, report=report, bounded=not yes,
                            force=force)  # fmt: skip
    with (
        naming_option("--candidates" if candidates != "none" else "--poses"),
        collections_skip_the_imports(),
    ):
        result, files = run_demo(settings, out, lambda msg: click.echo(f"… {msg}", err=True))
    if as_json:
        import json

        click.echo(json.dumps(demo_summary(result, files, out)))
    else:
        click.echo(format_demo(result, files))
