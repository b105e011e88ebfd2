"""`pincal info`: describe a model."""

from __future__ import annotations

import click

from pincal.cli.common import fail_cleanly


@click.command()
@click.argument("model")
@click.option("--preset", default=None, help="Parameter preset to analyse (default: all).")
@fail_cleanly
def info(model: str, preset: str | None) -> None:
    """Describe MODEL (bundled name, model directory or .urdf path)."""
    import numpy as np

    from pincal.model import load_mechanism, parameters
    from pincal.sensitivity import identifiability

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
