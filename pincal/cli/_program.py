"""`pincal compensate --program`: a G-code program of linear moves, compensated.

The program is read here, compensated by :func:`pincal.workflow.compensate_program`
(T' = FK_nominal(IK_calibrated(T)) for each move's target T) and written whole or not
at all; every line that is not a move is kept byte for byte.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import click

from pincal.cli._joint_terms import calibration_terms
from pincal.cli._paths import guard_paths

__all__ = ["run_program"]


def run_program(
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
    """`--program`: compensate ``program`` with ``calibration`` into ``out``; print a summary.

    Raises:
        OptionValueError: an option of target files given with ``--program``.
        MeasurementFormatError: a line the reader cannot follow, or a move before an
            axis the machine needs is known.
        UnreachablePoseError: targets the calibrated machine cannot reach on the
            nominal command's branch (their program lines named); nothing is written.
    """
    from pincal._files import read_text
    from pincal.errors import OptionValueError
    from pincal.io import atomic_write_text, read_calibration, read_gcode
    from pincal.workflow import compensate_program

    given = {"--components": components, "--skip-unreachable": skip or None,
             "--payload": payload, "--temperature": temperature}  # fmt: skip
    extra = [k for k, v in given.items() if v is not None]
    if extra:
        raise OptionValueError(
            f"{', '.join(extra)} do not apply to --program (the machine's own components, "
            "every move kept, the calibration's load and temperature)"
        )
    guard_paths({"CALIBRATION": calibration, "--program": program}, {"--out": out})
    start = time.perf_counter()
    name = Path(program).name
    prog = read_gcode(read_text(program, "G-code program"), name)
    cal = read_calibration(calibration)
    terms, _ = calibration_terms(cal, None, None)
    done = compensate_program(cal, prog, name, terms, allow)
    path = atomic_write_text(out, done.text)
    summary: dict[str, Any] = {
        "written": str(path),
        "moves": done.moves,
        "targets": done.targets,
        "lines": done.lines,
        "components": list(done.components),
        "largest_correction_mm": done.largest_correction_mm,
        "largest_correction_mrad": done.largest_correction_mrad,
        "seconds": time.perf_counter() - start,
    }
    if as_json:
        click.echo(json.dumps(summary))
        return
    click.echo(
        f"wrote {summary['written']}: {summary['moves']} moves ({summary['targets']} distinct "
        f"targets, {' '.join(summary['components'])}) compensated of {summary['lines']} lines; "
        f"largest correction {summary['largest_correction_mm']:.4g} mm / "
        f"{summary['largest_correction_mrad']:.4g} mrad; {summary['seconds']:.3g} s"
    )
