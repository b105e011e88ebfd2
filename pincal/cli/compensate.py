"""`pincal compensate`: actuator commands for target poses with a calibrated model."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal, overload

import click

from pincal.cli._joint_terms import (
    calibration_terms,
    payload_option,
    read_payload,
    temperature_option,
)
from pincal.cli._progress import counted
from pincal.cli.common import fail_cleanly, guard_paths

if TYPE_CHECKING:  # imported in the calls: the CLI starts without the model stack
    import numpy as np

    from pincal.compensation import Compensation, JointTermCorrection
    from pincal.io import PoseFile
    from pincal.model import Mechanism, Payload


@overload
def load_calibrated(
    spec: str,
    payload: Payload | None = None,
    with_terms: Literal[False] = False,
    temperature: float | None = None,
) -> tuple[Mechanism, str]: ...


@overload
def load_calibrated(
    spec: str,
    payload: Payload | None,
    with_terms: Literal[True],
    temperature: float | None = None,
) -> tuple[Mechanism, str, JointTermCorrection | None, str]: ...


def load_calibrated(
    spec: str,
    payload: Payload | None = None,
    with_terms: bool = False,
    temperature: float | None = None,
) -> tuple[Mechanism, str] | tuple[Mechanism, str, JointTermCorrection | None, str]:
    """The calibrated mechanism of a calibration directory (or a model spec, as in 0.1).

    With ``with_terms``: also the calibration's joint terms (at ``payload``, a
    :class:`~pincal.model.Payload` replacing the calibration's, and at ``temperature``
    °C for a thermal term) and a line on them.

    Returns:
        (mechanism, description of where it came from), and with ``with_terms`` the
        joint terms (None for a geometric calibration or a model) and their line.
    """
    from pincal.cli.common import announce
    from pincal.io import read_calibration
    from pincal.model import load_mechanism

    if Path(spec).is_dir() and not Path(spec, f"{Path(spec).name}.urdf").is_file():
        cal = read_calibration(spec)
        announce(cal)
        if with_terms:
            terms = calibration_terms(cal, payload, temperature)
            return cal.calibrated(), f"calibration {spec}", *terms
        return cal.calibrated(), f"calibration {spec}"
    if payload is not None:
        raise click.BadParameter(
            "a payload applies to a calibration directory with a compliance term",
            param_hint="--payload",
        )
    if temperature is not None:
        raise click.BadParameter(
            "a temperature applies to a calibration directory with a thermal term",
            param_hint="--temperature",
        )
    if with_terms:
        return load_mechanism(spec), f"model {spec}", None, ""
    return load_mechanism(spec), f"model {spec}"


@click.command()
@click.argument("calibration")
@click.option(
    "--targets",
    default=None,
    type=click.Path(dir_okay=False),
    help="Target poses file (pincal pose file, e.g. written by `pincal poses`).",
)
@click.option(
    "--program",
    default=None,
    type=click.Path(dir_okay=False),
    help="A G-code program of G0/G1 moves (X Y Z [A B C]) to rewrite into --out instead: "
    "each move's target compensated, every other line kept byte for byte.",
)
@click.option(
    "--out",
    required=True,
    type=click.Path(dir_okay=False),
    help="Commands CSV to write (with --program: the compensated program).",
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
@click.option(
    "--allow-branch-change",
    is_flag=True,
    help="Keep commands on another branch than their start (|Δq| > 0.5 rad / 50 mm from "
    "the nominal command, > π rad from another target's, or det of the actuator → pose "
    "Jacobian changing sign); listed. Default: refused.",
)
@payload_option(
    "Load at the targets for a calibration with a compliance term (kg; centre of mass in m "
    "in the tool frame), e.g. 5,0,0,0.08. It replaces calibrate's --payload (a payload link "
    "of the URDF itself stays); default: the load the calibration was fitted with."
)
@temperature_option(
    "Machine temperature at the targets [°C] for a calibration with a thermal term "
    "(calibrate --model geometric+temperature); default: its reference, 20 °C."
)
@click.option("--json", "as_json", is_flag=True, help="Print a JSON summary on stdout.")
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
    from pincal.compensation import compensate as run
    from pincal.compensation import compensation_components
    from pincal.errors import ColumnError, OptionValueError, UnreachablePoseError
    from pincal.io import read_pose_file, si_actuator_units, write_commands

    if (targets is None) == (program is None):
        raise OptionValueError("give exactly one of --targets (pose file) or --program (G-code)")
    if program is not None:
        _program(calibration, program, out, components, skip_unreachable, payload,
                 temperature, allow_branch_change, as_json)  # fmt: skip
        return
    assert targets is not None  # exactly one of --targets / --program, checked above
    guard_paths({"CALIBRATION": calibration, "--targets": targets}, {"--out": out})
    mech, origin, terms, terms_note = load_calibrated(
        calibration, read_payload(payload), with_terms=True, temperature=temperature
    )
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
    starts, start_note = _starts(pf, mech)
    with counted("compensating", unit="pose") as step:
        result = run(
            mech, poses, progress=step, components=comps,
            starts=starts, allow_branch_change=allow_branch_change, joint_terms=terms,
        )  # fmt: skip
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
    summary: dict[str, Any] = {  # the --json document
        "written": str(path),
        "source": origin,
        "model": mech.name,
        "components": list(result.components),
        "targets": len(poses),
        "commands": len(idx),
        "unreachable": list(result.unreachable),
        "reasons": {str(k): v for k, v in result.reasons.items()},
        "starts": start_note,
        "branch_changes": {str(k): v for k, v in (result.branch_changes or {}).items()},
        "branch_changes_allowed": allow_branch_change,
        "largest_step": _largest_steps(result, mech),
        "joint_terms": _terms_summary(result, terms, terms_note),
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
        click.echo(f"starts: {start_note}")
        if summary["joint_terms"]:
            click.echo(summary["joint_terms"]["line"])
        for line in _step_lines(summary["largest_step"]):
            click.echo(line)
        for k in result.unreachable:
            click.echo(f"  target {k}: {result.reasons[k]}")
        if allow_branch_change and result.branch_changes:
            click.echo(f"BRANCH CHANGES (allowed): targets {sorted(result.branch_changes)}")
            for k, why in sorted(result.branch_changes.items()):
                click.echo(f"  target {k}: {why}")


def _program(
    calibration: str,
    program: str,
    out: str,
    components: str | None,
    skip: bool,
    payload: str | None,
    temperature: float | None,
    allow: bool,
    as_json: bool,
) -> None:
    """`--program`: the compensated G-code program (see :mod:`pincal.cli._program`)."""
    from pincal.cli._program import compensate_program
    from pincal.errors import OptionValueError

    given = {"--components": components, "--skip-unreachable": skip or None,
             "--payload": payload, "--temperature": temperature}  # fmt: skip
    extra = [k for k, v in given.items() if v is not None]
    if extra:
        raise OptionValueError(
            f"{', '.join(extra)} do not apply to --program (the machine's own components, "
            "every move kept, the calibration's load and temperature)"
        )
    guard_paths({"CALIBRATION": calibration, "--program": program}, {"--out": out})
    summary = compensate_program(calibration, program, out, allow)
    if as_json:
        click.echo(json.dumps(summary))
        return
    click.echo(
        f"wrote {summary['written']}: {summary['moves']} moves ({summary['targets']} distinct "
        f"targets, {' '.join(summary['components'])}) compensated of {summary['lines']} lines; "
        f"largest correction {summary['largest_correction_mm']:.4g} mm / "
        f"{summary['largest_correction_mrad']:.4g} mrad; {summary['seconds']:.3g} s"
    )


def _starts(pf: PoseFile, mech: Mechanism) -> tuple[np.ndarray | None, str]:
    """The targets file's nominal commands in ``mech``'s actuator order, and a note."""
    import numpy as np

    if pf.q_act is None or not pf.actuated:
        return None, "no commands in the targets file: each target starts from the nearest solved"
    if sorted(pf.actuated) != sorted(mech.actuated):
        return None, (
            f"the targets file's actuator columns {list(pf.actuated)} are not the machine's "
            f"{list(mech.actuated)}: each target starts from the nearest solved one"
        )
    order = [list(pf.actuated).index(a) for a in mech.actuated]
    starts = np.asarray(pf.q_act, dtype=float)[:, order]
    return starts, f"the nominal command of each target ({len(starts)} in the targets file)"


def _largest_steps(result: Compensation, mech: Mechanism) -> dict:
    """Largest |Δq| from the start per actuator kind: {"rad"|"mm": {value, target, actuator}}."""
    out = {}
    for unit, shown, factor in (("rad", "rad", 1.0), ("m", "mm", 1e3)):
        step = result.largest_step(unit)
        if step is not None:
            value, i, k = step
            out[shown] = {"value": value * factor, "target": i, "actuator": mech.actuated[k]}
    return out


def _step_lines(steps: dict) -> list[str]:
    return [
        f"largest |Δq| from the start: {s['value']:.4g} {unit} "
        f"({s['actuator']}, target {s['target']})"
        for unit, s in steps.items()
    ]


def _terms_summary(
    result: Compensation, terms: JointTermCorrection | None, note: str
) -> dict | None:
    """The joint terms the commands include, and the largest deflection they undo."""
    import numpy as np

    if terms is None or result.deflection is None:
        return None
    d = np.abs(result.deflection[result.reachable])
    units = np.array(result.units)
    big = {
        "rad": float(d[:, units == "rad"].max(initial=0.0)) if d.size else 0.0,
        "m": float(d[:, units == "m"].max(initial=0.0)) if d.size else 0.0,
    }
    parts = [f"{big['rad'] * 1e3:.4f} mrad" if "rad" in units else "",
             f"{big['m'] * 1e3:.4f} mm" if "m" in units else ""]  # fmt: skip
    line = (f"commands include {note}: largest deflection undone "
            f"{' / '.join(p for p in parts if p)}")  # fmt: skip
    return {"line": line, "terms": terms.lines(), "largest_deflection": big}
