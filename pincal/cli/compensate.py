"""`pincal compensate`: actuator commands for target poses with a calibrated model."""

from __future__ import annotations

import json

import click

from pincal.cli._calibrated import calibrated_with_terms
from pincal.cli._compensate_options import compensate_options
from pincal.cli._joint_terms import read_payload
from pincal.cli._paths import guard_paths
from pincal.cli._program import run_program
from pincal.cli._progress import counted
from pincal.cli.common import fail_cleanly


@click.command()
@click.argument("calibration")
@compensate_options
@fail_cleanly
def compensate(
    calibration: str,
    targets: str | None,
    program: str | None,
    out: str,
    components: str | None,
    skip_unreachable: bool,
    allow_branch_change: bool,
    payload: str | None,
    temperature: float | None,
    as_json: bool,
) -> None:
    """Compensated actuator commands: inverse kinematics of the calibrated machine.

    CALIBRATION is the directory written by `pincal calibrate` (a model name or URDF
    is accepted too). Only the components the machine controls are imposed: the
    model's measured components unless --components says otherwise; a target file may
    give only those columns. The commands file states each actuator's unit.

    Each target's inverse kinematics starts from its own nominal command when the
    targets file carries the actuator columns (a `pincal poses` file does), otherwise
    from the command solved for the nearest target before it. A command on another
    branch than its start — an actuator moved more than 0.5 rad (revolute) or 50 mm
    (prismatic) from the target's nominal command, or more than π rad from another
    target's, or the determinant of the actuator → pose Jacobian changed sign (a
    singularity crossed) — is refused unless --allow-branch-change. The largest
    |Δq| from the starts is printed (rad for revolute, mm for prismatic actuators).

    A calibration with joint terms (`calibrate --model geometric+compliance`…) gives
    commands that include them: the deflection at each target's load is undone
    (--payload changes the load); a thermal term's expansion at --temperature °C too.

    \b
    Examples:
      pincal compensate cal/ --targets poses.csv --out commands.csv
      pincal compensate cal/ --targets targets.csv --components x,z,ry --out c.csv --json
      pincal compensate cal/ --targets big.csv --skip-unreachable --out c.csv
      pincal compensate cal/ --program part.ngc --out part_compensated.ngc

    A program (--program) is read as the controller reads it, through its nominal
    kinematics: each move's target T becomes T' = FK_nominal(IK_calibrated(T)), so that
    the controller's command for T' brings the calibrated machine to T. A B C [deg]
    rotate the measured frame from its home orientation (R_home·Rz(C)·Ry(B)·Rx(A)).
    Arcs, G91, G92, G10, G53, G28/G30 are refused with the line; a target that cannot be
    reached, or only on another branch, refuses the program (nothing written).
    """
    from pincal.errors import OptionValueError
    from pincal.io import si_actuator_units, write_commands
    from pincal.workflow import compensate_targets

    if (targets is None) == (program is None):
        raise OptionValueError("give exactly one of --targets (pose file) or --program (G-code)")
    if program is not None:
        run_program(calibration, program, out, components, skip_unreachable, payload,
                    temperature, allow_branch_change, as_json)  # fmt: skip
        return
    assert targets is not None  # exactly one of --targets / --program, checked above
    guard_paths({"CALIBRATION": calibration, "--targets": targets}, {"--out": out})
    mech, origin, terms, terms_note = calibrated_with_terms(
        calibration, read_payload(payload), temperature
    )
    with counted("compensating", unit="pose") as step:
        done = compensate_targets(
            mech, origin, targets, components, terms, terms_note,
            allow_branch_change, skip_unreachable, progress=step,
        )  # fmt: skip
    result = done.result
    path = write_commands(
        out, result.actuated, result.commands, done.reached,
        actuator_units=si_actuator_units(mech),
    )  # fmt: skip
    if as_json:
        click.echo(json.dumps(done.summary(str(path))))
    else:
        for line in done.lines(str(path)):
            click.echo(line)
