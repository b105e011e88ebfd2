"""`pincal import-tracker`: a tracker point export + controller log → a targets file."""

from __future__ import annotations

import json
from pathlib import Path

import click

from pincal.cli._limits import check_number
from pincal.cli._paths import guard_paths
from pincal.cli._tracker_options import TrackerArgs, tracker_options
from pincal.cli.common import ModelOptions, fail_cleanly, load_model, model_input, model_options

_FILE = click.Path(exists=True, dir_okay=False, path_type=Path)


@click.command("import-tracker")
@click.argument("points", type=_FILE)
@click.option(
    "--log", "log_path", required=True, type=_FILE, help="Controller log (one row per pose)."
)
@click.option("--targets", "targets_path", required=True, type=_FILE,
              help="Target coordinates in the measured frame (point, x, y, z).")  # fmt: skip
@click.option("--model", required=True, help="Model (bundled name, directory or .urdf).")
@click.option("--out", required=True, type=click.Path(dir_okay=False, path_type=Path),
              help="Targets measurement file to write (kind: targets).")  # fmt: skip
@tracker_options
@click.option("--json", "as_json", is_flag=True, help="Print a JSON summary.")
@model_options
@fail_cleanly
def import_tracker(
    points: Path,
    log_path: Path,
    targets_path: Path,
    model: str,
    out: Path,
    tracker: TrackerArgs,
    as_json: bool,
    model_opts: ModelOptions,
) -> None:
    """Pair a laser tracker's POINTS export with a controller log into a targets file.

    POINTS has one measured point per row (long format): a pose/group id and/or a
    time stamp, the target name and x, y, z in the machine base frame. --targets
    gives each target's x, y, z in the model's measured frame; --log has one row
    per pose with the pose id and/or time and one column per actuated joint.
    Delimiters , ; and tab and a decimal comma are detected; titles such as
    'X [mm]' carry their unit. The inputs are only read; OUT is written whole or
    not at all. See docs/examples/README.md for the formats.

    \b
    Examples:
      pincal import-tracker points.csv --log log.csv --targets targets_local.csv \\
          --model hexaslide_6pus --unit mm --log-length-unit mm --out targets.csv
      pincal import-tracker export.txt --log ctrl.csv --targets t.csv --model stewart_6ups \\
          --unit mm --match time --tolerance 0.2 --columns point=Name,time=Timestamp \\
          --out targets.csv --json
      pincal calibrate stewart_6ups --data targets.csv --out cal/
    """
    from pincal.io import import_tracker, write_target_measurements

    guard_paths(
        {"POINTS": points, "--log": log_path, "--targets": targets_path,
         "--model": model_input(model)},
        {"--out": out},
    )  # fmt: skip
    check_number(tracker.tolerance, "--tolerance", positive=True)
    check_number(tracker.point_std, "--point-std", positive=True)
    mech = load_model(model, model_opts)
    result = import_tracker(points, log_path, targets_path, mech, tracker.options())
    path = write_target_measurements(out, result.targets, length_unit=tracker.out_unit)
    summary = {
        "out": str(path),
        "model": mech.name,
        "frame": mech.measured_frame,
        "poses": len(result.pose_ids),
        "targets": list(result.targets.names),
        "match": result.match,
        "max_time_offset_s": result.max_time_offset,
    }
    if as_json:
        click.echo(json.dumps(summary))
        return
    extra = ""
    if result.max_time_offset is not None:
        extra = f", largest time offset {result.max_time_offset:.3g} s"
    click.echo(
        f"matched {len(result.pose_ids)} poses × {len(result.targets.names)} targets by "
        f"{result.match}{extra}"
    )
    click.echo(f"wrote {path}")
