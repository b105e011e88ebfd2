"""`pincal compensate --program`: a G-code program of linear moves, compensated.

The controller runs the program through its own (nominal) kinematics: a target T it
reads becomes the command q = IK_nominal(T). For the calibrated machine to reach T, the
program must ask for T' = FK_nominal(q_c), q_c = IK_calibrated(T) (the compensated
command, :func:`pincal.compensation.compensate`, started from IK_nominal(T) so that a
command on another branch is refused). Each move's axis words become T'; every other
line is kept byte for byte (:mod:`pincal.io._gcode`); the file is written whole or not
at all. Orientation words: A B C [deg] rotate the measured frame from its orientation
at home, ``R = R_home · Rz(C) · Ry(B) · Rx(A)``; only the components the machine
controls are read and rewritten (the model's measured components).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pinocchio as pin

from pincal.errors import ConvergenceError, MeasurementFormatError, UnreachablePoseError

__all__ = ["compensate_program"]

_AXIS_OF = {"x": "X", "y": "Y", "z": "Z", "rx": "A", "ry": "B", "rz": "C"}


def _target(values: dict[str, float], inch: bool, R_home: np.ndarray) -> pin.SE3:
    unit = 25.4e-3 if inch else 1e-3
    p = np.array([values.get(a, 0.0) for a in "XYZ"]) * unit
    a, b, c = (np.radians(values.get(k, 0.0)) for k in "ABC")
    return pin.SE3(R_home @ pin.rpy.rpyToMatrix(a, b, c), p)


def compensate_program(
    calibration: str, program: str, out: str, allow_branch_change: bool = False
) -> dict:
    """Compensate ``program`` with the calibration directory ``calibration`` into ``out``.

    Returns:
        A summary: moves, distinct targets, largest correction [mm, mrad], seconds.

    Raises:
        MeasurementFormatError: a line the reader cannot follow, or a move before an
            axis the machine needs is known.
        UnreachablePoseError: targets the calibrated machine cannot reach on the
            nominal command's branch (their program lines named); nothing is written.
    """
    from pincal._files import read_text
    from pincal.cli._joint_terms import calibration_terms
    from pincal.compensation import compensate, compensation_components
    from pincal.io import atomic_write_text, read_calibration, read_gcode, write_gcode

    start = time.perf_counter()
    name = Path(program).name
    prog = read_gcode(read_text(program, "G-code program"), name)
    cal = read_calibration(calibration)
    nominal, calibrated = cal.nominal(), cal.calibrated()
    terms, _ = calibration_terms(cal, None, None)
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
    for k, T in enumerate(targets):
        q = nominal.configuration(result.q_act[k], q)
        Tc = nominal.frame_placement(q)
        worst_p = max(worst_p, float(np.linalg.norm(Tc.translation - T.translation)))
        worst_r = max(worst_r, float(np.linalg.norm(pin.log3(T.rotation.T @ Tc.rotation))))
        abc = np.degrees(pin.rpy.matrixToRpy(R_home.T @ Tc.rotation))
        for line in lines_of[k]:
            unit = 25.4e-3 if inch_of[line] else 1e-3
            vals = dict(zip("XYZ", Tc.translation / unit, strict=True))
            vals |= dict(zip("ABC", abc, strict=True))
            new[line] = {a: float(vals[a]) for a in axes}
    path = atomic_write_text(out, write_gcode(prog, new))
    return {
        "written": str(path),
        "moves": len(prog.moves),
        "targets": len(targets),
        "lines": len(prog.lines),
        "components": list(comps),
        "largest_correction_mm": worst_p * 1e3,
        "largest_correction_mrad": worst_r * 1e3,
        "seconds": time.perf_counter() - start,
    }
