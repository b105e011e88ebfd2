"""`pincal compensate`: actuator commands for target poses with a calibrated model."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import click

from pincal.cli.common import fail_cleanly, guard_paths


def load_calibrated(spec: str):
    """The calibrated mechanism of a calibration directory (or a model spec, as in 0.1).

    Returns:
        (mechanism, description of where it came from).
    """
    from pincal.cli.common import announce
    from pincal.io import read_calibration
    from pincal.model import load_mechanism

    if Path(spec).is_dir() and not Path(spec, f"{Path(spec).name}.urdf").is_file():
        cal = read_calibration(spec)
        announce(cal)
        return cal.calibrated(), f"calibration {spec}"
    return load_mechanism(spec), f"model {spec}"


@click.command()
@click.argument("calibration")
@click.option(
    "--targets",
    required=True,
    type=click.Path(dir_okay=False),
    help="Target poses file (pincal pose file, e.g. written by `pincal poses`).",
)
@click.option(
    "--out", required=True, type=click.Path(dir_okay=False), help="Commands CSV to write."
)
@click.option(
    "--components",
    default=None,
    help="Pose components to reach, e.g. x,y,z (default: the model's measured components).",
)
@click.option(
    "--skip-unreachable",
    is_flag=True,
    help="Leave unreachable targets out (reported) instead of failing.",
)
@click.option("--json", "as_json", is_flag=True, help="Print a JSON summary on stdout.")
@fail_cleanly
def compensate(calibration, targets, out, components, skip_unreachable, as_json) -> None:
    """Compensated actuator commands: inverse kinematics of the calibrated machine.

    CALIBRATION is the directory written by `pincal calibrate` (a model name or URDF
    is accepted too). Only the components the machine controls are imposed: the
    model's measured components unless --components says otherwise; a target file may
    give only those columns. The commands file states each actuator's unit.

    \b
    Examples:
      pincal compensate cal/ --targets poses.csv --out commands.csv
      pincal compensate cal/ --targets targets.csv --components x,z,ry --out c.csv --json
      pincal compensate cal/ --targets big.csv --skip-unreachable --out c.csv
    """
    from pincal.compensation import compensate as run
    from pincal.compensation import compensation_components
    from pincal.errors import ColumnError, UnreachablePoseError
    from pincal.io import read_pose_file, si_actuator_units, write_commands

    guard_paths({"CALIBRATION": calibration, "--targets": targets}, {"--out": out})
    mech, origin = load_calibrated(calibration)
    comps = compensation_components(mech, components)
    pf = read_pose_file(targets)
    absent = [c for c in comps if c not in pf.components]
    if absent:
        raise ColumnError(
            f"{Path(targets).name} gives {' '.join(pf.components)} but the compensation "
            f"imposes {' '.join(comps)}: add columns {absent} or choose --components "
            f"{','.join(c for c in comps if c in pf.components) or 'x,y,z'}",
            missing=absent,
        )
    poses = pf.poses
    with click.progressbar(length=len(poses), label="compensating", file=sys.stderr) as bar:
        result = run(mech, poses, progress=lambda done, total: bar.update(1), components=comps)
    if result.unreachable and not skip_unreachable:
        first = result.unreachable[0]
        raise UnreachablePoseError(
            f"targets {list(result.unreachable)} are unreachable (target {first}: "
            f"{result.reasons[first]}); use --skip-unreachable to write the others"
        )
    idx = [i for i in range(len(poses)) if result.reachable[i]]
    path = write_commands(
        out, result.actuated, result.commands, idx, actuator_units=si_actuator_units(mech)
    )
    summary = {
        "written": str(path),
        "source": origin,
        "model": mech.name,
        "components": list(result.components),
        "targets": len(poses),
        "commands": len(idx),
        "unreachable": list(result.unreachable),
        "reasons": {str(k): v for k, v in result.reasons.items()},
    }
    if as_json:
        click.echo(json.dumps(summary))
    else:
        click.echo(
            f"compensating {' '.join(result.components)} of the measured frame "
            f"{mech.measured_frame} ({mech.mobility} degrees of freedom) with the {origin}"
        )
        msg = f"wrote {path}: {len(idx)} of {len(poses)} targets"
        if result.unreachable:
            msg += f"; unreachable: {list(result.unreachable)}"
        click.echo(msg)
        for k in result.unreachable:
            click.echo(f"  target {k}: {result.reasons[k]}")
