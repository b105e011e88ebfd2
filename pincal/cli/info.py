"""`pincal info`: describe a model."""

from __future__ import annotations

from typing import TYPE_CHECKING

import click

from pincal.cli.common import fail_cleanly

if TYPE_CHECKING:
    from pincal.model import Mechanism


def structure_lines(mech: Mechanism) -> list[str]:
    """The model's structure as text lines: joints, closures (rank at home), actuated,
    passive and idle joints, mobility, measured frame (and the automatic candidates),
    and the notes about joint ranges and kinds."""
    import numpy as np

    m = mech.model
    lines = [
        f"model {mech.name}  ({mech.source})",
        f"  joints: {m.njoints - 1} (nq {m.nq}, nv {m.nv})",
    ]
    for j in range(1, m.njoints):
        lines.append(f"    {m.names[j]:24s} {m.joints[j].shortname()}")
    Jc = mech.closure_jacobian(mech.q_home)
    total = int(np.linalg.matrix_rank(Jc)) if Jc.size else 0
    lines.append(f"  closures: {len(mech.closures)} (rank {total} of {Jc.shape[0]} rows at home)")
    k0 = 0
    for c in mech.closures:
        rows = Jc[k0 : k0 + c.size]
        k0 += c.size
        rank = int(np.linalg.matrix_rank(rows)) if rows.size else 0
        lines.append(f"    {c.frame_a} ↔ {c.frame_b}  [{c.label}]  rank {rank}/{c.size}")
    actuated = set(mech.actuated)
    passive = [
        m.names[j] for j in range(1, m.njoints) if m.names[j] not in actuated and m.nvs[j] > 0
    ]
    lines.append(f"  actuated: {', '.join(mech.actuated)}")
    lines.append(f"  passive: {', '.join(passive) or '-'}")
    if mech.idle_joints:
        lines.append(
            f"  free passive (not held by the actuators, do not move the measured frame): "
            f"{', '.join(mech.idle_joints)}"
        )
    lines.append(f"  mobility: {mech.mobility} (= {mech.n_actuated} actuated joints)")
    lines.append(
        f"  measured frame: {mech.measured_frame} [{' '.join(mech.measured_components)}]"
        f"{'' if mech.sidecar.measured_frame else ' (chosen automatically)'}"
    )
    others = [c for c in mech.measured_frame_candidates if c != mech.measured_frame][:5]
    if others:
        lines.append(f"    other candidates: {', '.join(others)}")
    for note in mech.notes:
        lines.append(f"  note: {note}")
    return lines


@click.command()
@click.argument("model")
@click.option("--preset", default=None, help="Parameter preset to analyse (default: all).")
@click.option(
    "--instrument",
    type=click.Choice(["distance", "sphere", "plane", "point"]),
    default=None,
    help="What this instrument identifies of the preset (default: first preset): rank, "
    "base set, absorbed combinations and the unseen motions in words.",
)
@fail_cleanly
def info(model: str, preset: str | None, instrument: str | None = None) -> None:
    """Describe MODEL (bundled name, model directory or .urdf path)."""
    import numpy as np

    from pincal.model import load_mechanism, parameters
    from pincal.sensitivity import identifiability

    mech = load_mechanism(model)
    for line in structure_lines(mech):
        click.echo(line)
    if instrument is not None:
        from pincal.identification import instrument_identifiability

        params = parameters(mech, preset or next(iter(mech.presets), "full"))
        for line in instrument_identifiability(mech, params, instrument).lines():
            click.echo(f"  {line}")
        return
    names = [preset] if preset else ["full", *mech.presets]
    for name in names:
        params = parameters(mech, name)
        ident = identifiability(mech, params, rng=np.random.default_rng(0))
        click.echo(f"  preset {name!r}: {len(params)} parameters, {ident.rank} identifiable")
        if preset:
            for line in ident.describe():
                click.echo(f"    {line}")
