"""`pincal compensate`: actuator commands for target poses with a calibrated model."""

from __future__ import annotations

import json
import sys

import click

from pincal.cli.common import fail_cleanly


@click.command()
@click.argument("model")
@click.option(
    "--targets",
    required=True,
    type=click.Path(dir_okay=False),
    help="Target poses file (pincal poses CSV).",
)
@click.option("--out", required=True, type=click.Path(dir_okay=False), help="Command CSV to write.")
@click.option(
    "--skip-unreachable",
    is_flag=True,
    help="Leave unreachable targets out (reported) instead of failing.",
)
@click.option("--json", "as_json", is_flag=True, help="Print a JSON summary on stdout.")
@fail_cleanly
def compensate(model, targets, out, skip_unreachable, as_json) -> None:
    """Compensated actuator commands: inverse kinematics of the calibrated MODEL.

    MODEL is typically the calibrated URDF written by `pincal calibrate`.
    """
    from pincal.compensation import compensate as run
    from pincal.errors import UnreachablePoseError
    from pincal.io import (
        read_poses,
        write_commands,
    )
    from pincal.model import load_mechanism

    mech = load_mechanism(model)
    poses = read_poses(targets)
    with click.progressbar(length=len(poses), label="compensating", file=sys.stderr) as bar:
        result = run(mech, poses, progress=lambda done, total: bar.update(1))
    if result.unreachable and not skip_unreachable:
        first = result.unreachable[0]
        raise UnreachablePoseError(
            f"targets {list(result.unreachable)} are unreachable (target {first}: "
            f"{result.reasons[first]}); use --skip-unreachable to write the others"
        )
    idx = [i for i in range(len(poses)) if result.reachable[i]]
    path = write_commands(out, result.actuated, result.commands, idx)
    summary = {
        "written": str(path),
        "targets": len(poses),
        "commands": len(idx),
        "unreachable": list(result.unreachable),
    }
    if as_json:
        click.echo(json.dumps(summary))
    else:
        msg = f"wrote {path}: {len(idx)} of {len(poses)} targets"
        if result.unreachable:
            msg += f"; unreachable: {list(result.unreachable)}"
        click.echo(msg)
