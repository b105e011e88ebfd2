"""`pincal demo`: the main job."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import click

from pincal.cli._limits import MAX_POSES, check_count, naming_option, yes_option
from pincal.cli.common import fail_cleanly


@contextmanager
def _collections_skip_the_imports() -> Iterator[None]:
    """Within: the objects that exist now (the imported modules) are frozen; at exit, all.

    Collections of Python's oldest generation scan every tracked object — numpy,
    Pinocchio and pincal loaded, ≈ 25 ms each — though during the demo they can only
    find the run's own garbage; and finalisation runs a last full collection (≈ 70 ms)
    just before the process ends and its memory goes back anyway. The objects frozen
    here are unfrozen on leaving unless the caller had frozen some (a process that
    runs the command and goes on, a test session, collects them again); the freeze at
    exit is registered once with :mod:`atexit`.
    """
    import atexit
    import gc

    atexit.unregister(gc.freeze)
    atexit.register(gc.freeze)
    frozen_before = gc.get_freeze_count()
    gc.freeze()
    try:
        yield
    finally:
        if not frozen_before:  # not undoing a freeze of the caller's
            gc.unfreeze()


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
    default="grid:4",
    show_default=True,
    help="Candidate poses for O1 selection (grid:LEVELS, random:N, oa:P) or 'none' for random.",
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
    from pincal.cli._demo_job import DemoSettings, format_demo, run_demo
    from pincal.design import parse_candidate_spec

    check_count(poses, "--poses", MAX_POSES, yes)
    check_count(validation, "--validation", MAX_POSES, yes)
    if candidates != "none":
        with naming_option("--candidates"):
            parse_candidate_spec(candidates)
    settings = DemoSettings(
        seed=seed,
        n_poses=poses,
        n_validation=validation,
        method=method,
        candidates=candidates,
        report=report,
        bounded=not yes,
        force=force,
    )
    with (
        naming_option("--candidates" if candidates != "none" else "--poses"),
        _collections_skip_the_imports(),
    ):
        result = run_demo(settings, out, progress=lambda msg: click.echo(f"… {msg}", err=True))
    if as_json:
        import json

        r = result.result
        click.echo(
            json.dumps(
                {
                    "model": result.nominal.name,
                    "parameters": len(result.params),
                    "iterations": int(r.iterations),
                    "reduced_chi2": float(r.reduced_chi2),
                    "validation_before": result.before.summary(),
                    "validation_after": result.after.summary(),
                    "calibration": str(out),
                    "files": [str(f) for f in result.files],
                }
            )
        )
    else:
        click.echo(format_demo(result))
