"""The ``pincal`` command.

Exit codes: 0 success; 1 a pincal error (bad input, unreachable pose, …) reported
as one line on stderr; 2 wrong command-line usage. ``--debug`` shows tracebacks.
"""

from __future__ import annotations

import logging
import sys
from functools import wraps

import click

from pincal.errors import PincalError


def _fail_cleanly(func):
    """Report PincalError (and file errors) as one line, exit code 1."""

    @wraps(func)
    def wrapper(*args, **kwargs):
        ctx = click.get_current_context()
        try:
            return func(*args, **kwargs)
        except (PincalError, OSError, ValueError) as exc:
            if ctx.find_root().obj and ctx.find_root().obj.get("debug"):
                raise
            click.echo(f"pincal: error: {type(exc).__name__}: {exc}", err=True)
            sys.exit(1)

    return wrapper


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.option("--debug", is_flag=True, help="Show tracebacks and debug logging.")
@click.pass_context
def main(ctx: click.Context, debug: bool) -> None:
    """Kinematic calibration of parallel machines and serial chains.

    \b
    Examples:
      pincal demo                      full simulated Stewart calibration
      pincal info stewart_6ups         joints, closures, presets, identifiability
    """
    ctx.ensure_object(dict)
    ctx.obj["debug"] = debug
    logging.basicConfig(level=logging.DEBUG if debug else logging.WARNING)


@main.command()
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
@_fail_cleanly
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


@main.command()
@click.argument("model")
@click.option("--preset", default=None, help="Parameter preset to analyse (default: all).")
@_fail_cleanly
def info(model: str, preset: str | None) -> None:
    """Describe MODEL (bundled name, model directory or .urdf path)."""
    import numpy as np

    from pincal.identifiability import identifiability
    from pincal.mechanism import load_mechanism
    from pincal.parameters import parameters

    mech = load_mechanism(model)
    m = mech.model
    click.echo(f"model {mech.name}  ({mech.source})")
    click.echo(f"  joints: {m.njoints - 1} (nq {m.nq}, nv {m.nv})")
    for j in range(1, m.njoints):
        click.echo(f"    {m.names[j]:24s} {m.joints[j].shortname()}")
    click.echo(f"  closures: {len(mech.closures)}")
    for c in mech.closures:
        click.echo(f"    {c.frame_a} ↔ {c.frame_b}  [{c.label}]")
    click.echo(f"  actuated: {', '.join(mech.actuated)}")
    click.echo(f"  mobility: {mech.mobility} (= {mech.n_actuated} actuated joints)")
    click.echo(f"  measured frame: {mech.measured_frame} [{' '.join(mech.measured_components)}]")
    names = [preset] if preset else ["full", *mech.presets]
    for name in names:
        params = parameters(mech, name)
        ident = identifiability(mech, params, rng=np.random.default_rng(0))
        click.echo(f"  preset {name!r}: {len(params)} parameters, {ident.rank} identifiable")
        if preset:
            for line in ident.describe():
                click.echo(f"    {line}")


if __name__ == "__main__":  # pragma: no cover
    main()
