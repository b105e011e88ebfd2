"""`pincal demo`: the main job."""

from __future__ import annotations

import click

from pincal.cli.common import fail_cleanly


@click.command()
@click.option("--seed", default=7, show_default=True, help="Random seed of the simulation.")
@click.option("--poses", default=30, show_default=True, help="Number of measurement poses.")
@click.option("--validation", default=60, show_default=True, help="Fresh validation poses.")
@click.option(
    "--method",
    type=click.Choice(["gauss-newton", "lm"]),
    default="gauss-newton",
    show_default=True,
)
@click.option("--out", default="pincal-out", show_default=True, help="Output directory.")
@fail_cleanly
def demo(seed: int, poses: int, validation: int, method: str, out: str) -> None:
    """Simulated calibration of the bundled 6-UPS Stewart platform (42 parameters).

    Draws an "actual" machine (0.5 mm errors), simulates a laser-tracker campaign
    (noise 0.01 mm / 0.02 mrad), identifies the parameters, validates on fresh poses
    and writes the calibrated URDF to OUT.
    """
    from pincal.demo import DemoSettings, format_demo, run_demo

    settings = DemoSettings(seed=seed, n_poses=poses, n_validation=validation, method=method)
    result = run_demo(settings, out, progress=lambda msg: click.echo(f"… {msg}", err=True))
    click.echo(format_demo(result))
