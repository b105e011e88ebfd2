"""`pincal import-sockets`: a lab's plain CSV of socket seatings → a pincal sockets file."""

from __future__ import annotations

import json
from pathlib import Path

import click

from pincal.cli._paths import guard_paths
from pincal.cli._socket_args import parse_ball, parse_distance
from pincal.cli.common import ModelOptions, fail_cleanly, load_model, model_input, model_options

__all__ = ["import_sockets"]


@click.command("import-sockets")
@click.argument("table", type=click.Path(exists=True, dir_okay=False, path_type=Path))
@click.option("--model", required=True, help="Model (name, directory, .urdf or sidecar YAML).")
@click.option("--socket-column", default="socket", show_default=True,
              help="Title of the column naming each row's socket (numbers or names).")  # fmt: skip
@click.option("--distance", "distances", multiple=True, metavar="A,B,VALUE,STD",
              help="A known distance between sockets A and B and its 1σ [--length-unit] "
              "(repeat). Without one the length scale is unidentifiable.")  # fmt: skip
@click.option("--std", type=float, default=0.005, show_default=True,
              help="1σ of one seating of the ball centre, per axis [--length-unit].")  # fmt: skip
@click.option("--plate", default="plate", show_default=True,
              help="The plate's name (files of one plate share its socket centres).")  # fmt: skip
@click.option("--ball", default="0,0,0", show_default=True,
              help="Ball centre in the flange frame X,Y,Z [--length-unit] or unknown.")  # fmt: skip
@click.option("--length-unit", type=click.Choice(["m", "mm", "um"]), default="mm",
              show_default=True, help="Unit of --std, --distance and --ball.")  # fmt: skip
@click.option("--columns", default=None, metavar="COLUMN=JOINT,…",
              help="Joint columns named otherwise than the URDF joints.")  # fmt: skip
@click.option("--joint-units", default=None,
              help="deg (every angle), or 'angle=deg length=mm' / 'JOINT=UNIT …'.")  # fmt: skip
@click.option("--joint-reference", default=None,
              help="home or 'JOINT=VALUE …' [rad, m]: readings relative to that pose.")  # fmt: skip
@click.option("--out", required=True, type=click.Path(dir_okay=False, path_type=Path),
              help="Sockets file to write ('# pincal sockets 1', SI).")  # fmt: skip
@click.option("--json", "as_json", is_flag=True, help="Print a JSON summary.")
@model_options
@fail_cleanly
def import_sockets(
    table: Path,
    model: str,
    socket_column: str,
    distances: tuple[str, ...],
    std: float,
    plate: str,
    ball: str,
    length_unit: str,
    columns: str | None,
    joint_units: str | None,
    joint_reference: str | None,
    out: Path,
    as_json: bool,
    model_opts: ModelOptions,
) -> None:
    """Read a plain CSV of ball-in-socket seatings (no pincal header) into a sockets file.

    TABLE has one row per seating: a column per actuated joint (named as the URDF
    joints, or mapped by --columns or the sidecar's `columns`) and a column naming the
    socket (--socket-column). The declarations the table lacks are given here. The
    inputs are only read; OUT is written whole or not at all.

    \b
    Examples:
      pincal import-sockets lab.csv --model ur5 --socket-column hole --distance 1,2,50,0.002 \\
          --columns J1=shoulder_pan_joint,J2=shoulder_lift_joint,… --joint-units deg \\
          --out sockets.csv
      pincal import-sockets lab.csv --model ur5 --distance A,B,50,0.002 --out s.csv --json
      pincal calibrate ur5 --data sockets.csv --out cal/
    """
    from pincal.io import SocketTable, parse_mapping, read_socket_table, write_socket_data

    guard_paths({"TABLE": table, "--model": model_input(model)}, {"--out": out})
    spec = SocketTable(
        column=socket_column,
        std=std,
        distances=tuple(parse_distance(d) for d in distances),
        plate=plate,
        ball=parse_ball(ball),
        length_unit=length_unit,
        columns=parse_mapping(columns, "--columns"),
        joint_units=joint_units,
        joint_reference=joint_reference,
    )
    mech = load_model(model, model_opts)
    data = read_socket_table(table, mech, spec)
    path = write_socket_data(out, data)
    if as_json:
        click.echo(json.dumps({
            "out": str(path), "model": mech.name, "frame": data.frame, "seatings": len(data),
            "sockets": {s: data.socket.count(s) for s in data.sockets},
            "distances_mm": [[k.a, k.b, k.value * 1e3, k.std * 1e3]
                             for k in data.plate.distances],
        }))  # fmt: skip
        return
    counts = ", ".join(f"{s} ×{data.socket.count(s)}" for s in data.sockets)
    known = "; ".join(f"{k.a}–{k.b} {k.value * 1e3:.6g} mm" for k in data.plate.distances)
    if not data.plate.distances:
        from pincal.measure import SCALE_MESSAGE

        click.echo(f"pincal: warning: {table.name}: no known distance: {SCALE_MESSAGE}", err=True)
    click.echo(f"{len(data)} seatings in sockets {counts}; known distances: {known or 'none'}")
    click.echo(f"wrote {path}")
