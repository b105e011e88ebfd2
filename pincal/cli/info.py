"""`pincal info`: describe a model."""

from __future__ import annotations

import click

from pincal.cli._kinds import InstrumentChoice
from pincal.cli.common import ModelOptions, fail_cleanly, load_model, model_options


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

    from pincal.cli._joint_terms import (
        THERMAL_SPAN_C,
        carrying,
        compliance_note,
        read_payload,
        temperature_note,
    )
    from pincal.cli._progress import counted
    from pincal.model import split_model
    from pincal.sensitivity import parameters
    from pincal.workflow import describe_presets, structure_lines

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
    with counted("identifiability", unit="set") as step:  # random-pose Jacobian SVDs
        found = describe_presets(mech, preset, terms, THERMAL_SPAN_C, progress=step)
    notes = [n for n in (compliance_note(terms, load), temperature_note(terms)) if n]
    if not as_json:
        for line in [*found.lines, *(f"  note: {n}" for n in notes)]:
            click.echo(line)
        return
    doc = {
        "model": mech.name,
        "source": None if mech.source is None else str(mech.source),
        "actuated": list(mech.actuated),
        "mobility": int(mech.mobility),
        "closures": len(mech.closures),
        "measured_frame": mech.measured_frame,
        "measured_components": list(mech.measured_components),
        "presets": found.presets,
        "base_preset": found.base,
        "notes": list(mech.notes) + notes,
    }
    click.echo(json.dumps(doc))
