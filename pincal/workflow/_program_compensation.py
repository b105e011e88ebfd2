"""A G-code program of linear moves compensated as ``pincal compensate --program`` does it.

The controller runs the program through its own (nominal) kinematics: a target T it
reads becomes the command q = IK_nominal(T). For the calibrated machine to reach T, the
program must ask for T' = FK_nominal(q_c), q_c = IK_calibrated(T) (the compensated
command, :func:`pincal.compensation.compensate`, started from IK_nominal(T) so that a
command on another branch is refused). Each move's axis words become T'; every other
line is kept byte for byte (:func:`pincal.io.write_gcode`). Orientation words: A B C
[deg] rotate the measured frame from its orientation at home,
``R = R_home · Rz(C) · Ry(B) · Rx(A)``; only the components the machine controls are
read and rewritten (the model's measured components). Nothing is written here:
:func:`compensate_program` returns the program's new text.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pincal.compensation import JointTermCorrection, compensate, compensation_components
from pincal.errors import ConvergenceError, MeasurementFormatError, UnreachablePoseError
from pincal.io import CalibrationDirectory, GcodeProgram, write_gcode

__all__ = ["CompensatedProgram", "compensate_program"]

_AXIS_OF = {"x": "X", "y": "Y", "z": "Z", "rx": "A", "ry": "B", "rz": "C"}


@dataclass(frozen=True)
class CompensatedProgram:
    """A program as :func:`compensate_program` rewrote it.

    Attributes:
        text: the compensated program (every line that is not a move as it was).
        moves: the number of moves.
        targets: the number of distinct targets among them (each compensated once).
        lines: the number of lines of the program.
        components: the components rewritten (x y z rx ry rz order).
        largest_correction_mm: the largest distance T → T' over the position axes the
            program controls [mm].
        largest_correction_mrad: the largest change of the angles A B C the program
            controls, as a vector norm [mrad].
    """

    text: str
    moves: int
    targets: int
    lines: int
    components: tuple[str, ...]
    largest_correction_mm: float
    largest_correction_mrad: float


def _target(values: dict[str, float], inch: bool, R_home: np.ndarray) -> pin.SE3:
    unit = 25.4e-3 if inch else 1e-3
    p = np.array([values.get(a, 0.0) for a in "XYZ"]) * unit
    a, b, c = (np.radians(values.get(k, 0.0)) for k in "ABC")
    return pin.SE3(R_home @ pin.rpy.rpyToMatrix(a, b, c), p)


def compensate_program(
    cal: CalibrationDirectory,
    prog: GcodeProgram,
    name: str,
    terms: JointTermCorrection | None = None,
    allow_branch_change: bool = False,
) -> CompensatedProgram:
    """Compensate the moves of ``prog`` with the calibration ``cal``.

    Args:
        cal: the calibration directory (its nominal and calibrated mechanisms).
        prog: the program (:func:`pincal.io.read_gcode`); lengths in mm or inch, angles
            A B C in degrees.
        name: the program's name in messages (its file name).
        terms: the calibration's joint terms, included in the commands (None: none).
        allow_branch_change: keep commands on another branch than the nominal command.

    Raises:
        MeasurementFormatError: a move before an axis the machine needs is known.
        UnreachablePoseError: targets the calibrated machine cannot reach on the
            nominal command's branch (their program lines named).
    """
    nominal, calibrated = cal.nominal(), cal.calibrated()
    comps = compensation_components(calibrated, None)
    axes = [_AXIS_OF[c] for c in comps]
    R_home = nominal.frame_placement(nominal.q_home).rotation
    keys: dict[tuple, int] = {}
    targets: list[pin.SE3] = []
    lines_of: list[list[int]] = []
    for move in prog.moves:
        unknown = [a for a in axes if a not in move.values]
        if unknown:
            raise MeasurementFormatError(
                f"{name} line {move.line + 1}: axis {' '.join(unknown)} not known yet (the "
                f"machine controls {' '.join(axes)}); give it on the first move"
            )
        key = (move.inch, *(round(move.values[a], 9) for a in axes))
        if key not in keys:
            keys[key] = len(targets)
            targets.append(_target(move.values, move.inch, R_home))
            lines_of.append([])
        lines_of[keys[key]].append(move.line)
    starts = np.full((len(targets), nominal.n_actuated), np.nan)
    guess, failed = nominal.q_home, {}
    for k, T in enumerate(targets):
        try:
            guess = nominal.inverse_configuration(T, guess)
            starts[k] = nominal.actuators_of(guess)
        except ConvergenceError as exc:
            failed[k] = f"the nominal controller cannot reach it ({exc})"
            guess = nominal.q_home
    result = compensate(
        calibrated, targets, components=comps, starts=starts,
        allow_branch_change=allow_branch_change, joint_terms=terms,
    )  # fmt: skip
    bad = {**{k: result.reasons[k] for k in result.unreachable}, **failed}
    if bad:
        shown = sorted(bad)[:5]
        raise UnreachablePoseError(
            f"{len(bad)} targets of {name} cannot be compensated; nothing written: "
            + "; ".join(f"line {lines_of[k][0] + 1}: {bad[k]}" for k in shown)
            + (" …" if len(bad) > len(shown) else "")
        )
    inch_of = {m.line: m.inch for m in prog.moves}
    new: dict[int, dict[str, float]] = {}
    worst_p = worst_r = 0.0
    q = nominal.q_home
    # the correction over the axes the program controls (the others are not written)
    moved = [i for i, a in enumerate("XYZ") if a in axes]
    turned = [i for i, a in enumerate("ABC") if a in axes]
    for k, T in enumerate(targets):
        q = nominal.configuration(result.q_act[k], q)
        Tc = nominal.frame_placement(q)
        worst_p = max(worst_p, float(np.linalg.norm((Tc.translation - T.translation)[moved])))
        abc = np.degrees(pin.rpy.matrixToRpy(R_home.T @ Tc.rotation))
        abc_t = np.degrees(pin.rpy.matrixToRpy(R_home.T @ T.rotation))
        turn = (abc - abc_t + 180.0) % 360.0 - 180.0  # [deg], wrapped
        worst_r = max(worst_r, float(np.linalg.norm(np.radians(turn)[turned])))
        for line in lines_of[k]:
            unit = 25.4e-3 if inch_of[line] else 1e-3
            vals = dict(zip("XYZ", Tc.translation / unit, strict=True))
            vals |= dict(zip("ABC", abc, strict=True))
            new[line] = {a: float(vals[a]) for a in axes}
    return CompensatedProgram(
        text=write_gcode(prog, new),
        moves=len(prog.moves),
        targets=len(targets),
        lines=len(prog.lines),
        components=tuple(comps),
        largest_correction_mm=worst_p * 1e3,
        largest_correction_mrad=worst_r * 1e3,
    )
