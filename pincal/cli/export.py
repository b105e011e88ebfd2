"""`pincal export`: a calibration as a controller's own kinematic parameters."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path

import click

from pincal.cli._paths import guard_paths
from pincal.cli.common import announce, fail_cleanly


class FormatChoice(click.Choice):
    """``click.Choice`` over the registered export formats, read when parsed."""

    name = "format"

    def __init__(self) -> None:
        super().__init__(["generic-table"])

    @property  # type: ignore[override]
    def choices(self) -> Sequence[str]:
        """The registered format names."""
        from pincal.export import FORMATS

        return tuple(FORMATS)

    @choices.setter
    def choices(self, value: Sequence[str]) -> None:
        """Set by ``click.Choice.__init__``; the registry is the source."""


@click.command("export")
@click.argument("calibration", type=click.Path(path_type=Path))
@click.option(
    "--format",
    "format_name",
    type=FormatChoice(),
    required=True,
    help="Controller format (see docs/cli.md, 'Export to a controller').",
)
@click.option(
    "--out",
    type=click.Path(dir_okay=False, path_type=Path),
    required=True,
    help="File to write (the projection report is its header comment).",
)
@click.option(
    "--poses",
    type=click.IntRange(1, 100_000),
    default=200,
    show_default=True,
    help="Random workspace poses the projection is judged on.",
)
@click.option(
    "--seed", type=click.IntRange(0), default=0, show_default=True, help="Seed of those poses."
)
@click.option("--json", "as_json", is_flag=True, help="Print the projection as JSON.")
@fail_cleanly
def export(
    calibration: Path, format_name: str, out: Path, poses: int, seed: int, as_json: bool
) -> None:
    """Write the calibration in CALIBRATION as a controller's parameters.

    Formats: linuxcnc-genhexkins (hexapod strut ends as HAL setp lines, per-joint
    offsets), generic-table (every joint placement calibrated vs nominal and the zero
    offsets, any machine, YAML), dh-standard / dh-modified (a DH table fitted to a
    serial arm's joint axes, with base and tool transforms, YAML), dh-offsets-lengths
    (zero offsets and link lengths on the nominal DH table), klipper-delta /
    linuxcnc-lineardeltakins / rotary-delta (delta parameters), volumetric-map (an
    error map and command corrections on a workspace grid, CSV).

    An export is a projection: over random workspace poses it reports the RMS and max
    position / orientation difference between the controller's own equations with
    the written numbers and the calibrated model, and what the format cannot express,
    on stdout and in the file's header.

    \b
    Examples:
      pincal export cal/ --format linuxcnc-genhexkins --out hexapod.hal
      pincal export ur5_cal/ --format dh-standard --out ur5_dh.yaml
    """
    from pincal.export import CalibratedMachine, export_calibration, write_export
    from pincal.io import read_calibration

    guard_paths({"CALIBRATION": calibration}, {"--out": out})
    cal = read_calibration(calibration)
    announce(cal)
    done = export_calibration(
        CalibratedMachine.from_directory(cal), format_name, poses=poses, seed=seed
    )
    write_export(done, out)
    if as_json:
        click.echo(json.dumps({"out": str(out), "projection": done.projection.to_dict()}))
        return
    for line in done.projection.lines():
        click.echo(line)
    click.echo(f"wrote {out}")
