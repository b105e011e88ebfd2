"""`pincal info`: describe a model."""

from __future__ import annotations

from typing import TYPE_CHECKING

import click

from pincal.cli._kinds import InstrumentChoice
from pincal.cli.common import ModelOptions, fail_cleanly, load_model, model_options

if TYPE_CHECKING:
    from pincal.model import Mechanism


def structure_lines(mech: Mechanism, frame_given: bool = False) -> list[str]:
    """The model's structure as text lines.

    Lists joints, closures (rank at home), actuated, passive and idle joints, mobility,
    measured frame (and the automatic candidates), and the notes about joint ranges
    and kinds.
    """
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
        f"{'' if mech.sidecar.measured_frame or frame_given else ' (chosen automatically)'}"
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
    type=InstrumentChoice(socket=False),
    default=None,
    help="What this instrument identifies of the preset (default: first preset): rank, "
    "base set, absorbed combinations and the unseen motions in words.",
)
@click.option(
    "--model",
    "error_model",
    default="geometric",
    show_default=True,
    help="Error model analysed: geometric[+compliance][+gain][+harmonics]"
    "[+strut-compliance] (joint-space terms on every actuated joint, or on every "
    "fixed-length strut, beside each preset's parameters).",
)
@click.option(
    "--payload",
    default=None,
    metavar="MASS[,X,Y,Z]",
    help="Payload on the tool (kg; centre of mass in m in the tool frame), e.g. 20,0,0,0.1.",
)
@click.option("--json", "as_json", is_flag=True, help="Print a JSON description on stdout.")
@model_options
@fail_cleanly
def info(
    model: str,
    preset: str | None,
    instrument: str | None,
    error_model: str,
    payload: str | None,
    as_json: bool,
    model_opts: ModelOptions,
) -> None:
    """Describe MODEL (bundled name, model directory, .urdf or MJCF .xml path).

    
    Examples:
      pincal info stewart_6ups
      pincal info wedge3 --preset patent
      pincal info stewart_6ups --instrument distance    what a ballbar cannot see
      pincal info models/pkm5 --json
      pincal info tiago --frame arm_tool_link --lock torso_lift_joint=0.2
      pincal info ur5 --preset base --model geometric+compliance+gain
      pincal info my_tiago.yaml                 a sidecar file with `robot: tiago`
    """
    import json

    import numpy as np

    from pincal.cli._joint_terms import (
        THERMAL_SPAN_C,
        carrying,
        compliance_note,
        read_payload,
        temperature_note,
    )
    from pincal.cli._progress import counted
    from pincal.model import (
        degenerate_translations,
        describe_direction,
        direction_record,
        sample_actuators,
        split_model,
        with_joint_terms,
    )
    from pincal.sensitivity import BASE_POSES, base_set, identifiability, parameters

    terms = split_model(error_model)
    load = read_payload(payload)
    mech = carrying(load_model(model, model_opts, quiet=True), load)
    if not as_json:
        for line in structure_lines(mech, bool(model_opts.frame)):
            click.echo(line)
    if instrument is not None:
        from pincal.identification import instrument_identifiability

        params = parameters(mech, preset or next(iter(mech.presets), "full"))
        lines = instrument_identifiability(mech, params, instrument).lines()
        if as_json:
            click.echo(json.dumps({"model": mech.name, "instrument": instrument, "lines": lines}))
        else:
            for line in lines:
                click.echo(f"  {line}")
        return
    names = [preset] if preset else ["full", *mech.presets]
    with_base = preset is None and "base" not in mech.presets
    steps = len(names) + with_base
    sets = [with_joint_terms(mech, parameters(mech, name), terms) for name in names]
    idents: list = []
    rows, cond = None, None
    if "temperature" in terms:  # random poses at temperatures spread over THERMAL_SPAN_C
        rows = sample_actuators(mech, 60, np.random.default_rng(0))
        cond = {"temperature": np.random.default_rng(1).uniform(*THERMAL_SPAN_C, len(rows))}
    with counted("identifiability", unit="set") as step:  # random-pose Jacobian SVDs
        for params in sets:
            idents.append(identifiability(mech, params, rows, rng=np.random.default_rng(0),
                                          conditions=cond))  # fmt: skip
            step(len(idents), steps)
        found = base_set(mech) if with_base else None  # = parameters(mech, "base")
        step(steps, steps)
    presets = []
    for name, params, ident in zip(names, sets, idents, strict=True):
        n_breaking = int(ident.breaks_closure.size)
        presets.append(
            {
                "preset": name,
                "parameters": len(params),
                "identifiable": int(ident.rank),
                "breaks_closure": n_breaking,
                "explanation": list(ident.describe()) if preset else [],
                "directions": [direction_record(mech, p.name, p.joint, p.dof, p.twist)
                               for p in params.parameters] if preset else [],
            }
        )  # fmt: skip
        if as_json:
            continue
        breaking = f", {n_breaking} break loop closure" if n_breaking else ""
        click.echo(
            f"  preset {name!r}: {len(params)} parameters, {ident.rank} identifiable{breaking}"
        )
        if preset:
            for line in ident.describe():
                click.echo(f"    {line}")
            click.echo("    what each parameter moves, in its parent link's frame (hold one in a "
                       "preset by {joints: J, along_parent: x|y|z|[a,b,c], hold: true}; "
                       "about_parent for rotations):")  # fmt: skip
            for p in params.parameters:
                click.echo(f"      {describe_direction(mech, p.name, p.joint, p.dof, p.twist)}")
    base = None
    if found is not None:  # the base preset, with what it leaves out
        n_base, n_degenerate = len(found.params), len(degenerate_translations(mech))
        base = {"parameters": n_base, "degenerate_translations_left_out": n_degenerate}
        base["weak_directions_left_out"] = found.weak
        if not as_json:
            click.echo(base_line(mech, n_base, n_degenerate, BASE_POSES))
            if found.note():
                click.echo(f"    {found.note()}")
    note = compliance_note(terms, load)
    if note and not as_json:
        click.echo(f"  note: {note}")
    if temperature_note(terms) and not as_json:
        click.echo(f"  note: {temperature_note(terms)}")
    if as_json:
        doc = {
            "model": mech.name,
            "source": None if mech.source is None else str(mech.source),
            "actuated": list(mech.actuated),
            "mobility": int(mech.mobility),
            "closures": len(mech.closures),
            "measured_frame": mech.measured_frame,
            "measured_components": list(mech.measured_components),
            "presets": presets,
            "base_preset": base,
            "notes": list(mech.notes) + [n for n in (note, temperature_note(terms)) if n],
        }
        click.echo(json.dumps(doc))


def reduction_line(preset: str, rank: int, n: int) -> str:
    """The one line `pincal poses` and `pincal calibrate` print when reducing a preset.

    Printed when a rank-deficient preset is reduced to its identifiable base set.
    """
    return (
        f"pincal: preset {preset!r}: {rank} of {n} parameters identifiable; using its "
        f"identifiable base set (`pincal info MODEL` offers it as the 'base' preset)"
    )


def base_line(mech: Mechanism, n_base: int, n_degenerate: int, n_poses: int) -> str:
    """The line of `pincal info` that offers the identifiable base set as a preset."""
    left = (
        f"; {n_degenerate} translations between coincident passive axes left out"
        if n_degenerate
        else ""
    )
    return (
        f"  preset 'base': {n_base} parameters, all identifiable (the identifiable base set "
        f"of 'full' over {n_poses} random poses{left}); use it with --params base "
        f"(simulate, calibrate) or --preset base (poses, info)"
    )
