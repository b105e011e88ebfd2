"""``pincal calibrate --data FILE…``: pose or instrument files calibrated, printed, written.

The calibration itself is :func:`pincal.workflow.calibrate_pose_file` (or
:func:`pincal.workflow.calibrate_instrument_files`); this module prints its progress,
applies the gate (refusal or ``--force``) and writes the calibration directory.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

import click

from pincal.cli._calibrate_text import result_json
from pincal.cli._limits import check_data_rows
from pincal.cli.common import ModelOptions, load_model, model_record, model_source

if TYPE_CHECKING:  # imported in the calls: the CLI starts without the model stack
    from pincal.identification import GateLimits
    from pincal.model import Payload
    from pincal.workflow import Steps

__all__ = ["calibrate_poses", "is_instrument_file", "refuse_marker_options"]


def is_instrument_file(path: str) -> bool:
    """True for an instrument file (``# pincal instrument`` / ``# pincal sockets``)."""
    from pincal.errors import PincalError
    from pincal.io import is_instrument_file as starts_as_instrument_file

    try:
        return starts_as_instrument_file(path)
    except PincalError:
        return False  # the measurement reader reports the problem


def refuse_marker_options(
    prior_spec: str | None, orientation_columns: str | None, orientation: str | None
) -> None:
    """Refuse the marker-table options on a pose / instrument file.

    Raises:
        click.BadParameter: ``--prior``, ``--orientation-columns`` or ``--orientation``.
    """
    if prior_spec is not None:
        raise click.BadParameter("--prior applies to marker calibrations (--link)",
                                 param_hint="--prior")  # fmt: skip
    if orientation_columns is not None or orientation is not None:
        raise click.BadParameter("--orientation-columns and --orientation apply to marker "
                                 "tables (--link); a pose file names its orientation columns "
                                 "itself", param_hint="--orientation-columns")  # fmt: skip


def _steps() -> Steps:
    """The workflow's progress on stderr: lines, warnings, bars (or plain lines)."""
    from pincal.cli._progress import counted, iterations
    from pincal.workflow import Steps

    return Steps(
        say=lambda line: click.echo(f"… {line}", err=True),
        warn=lambda w: click.echo(f"pincal: warning: {w}", err=True),
        iterations=iterations,
        counted=counted,
    )


def calibrate_poses(
    model: str, model_opts: ModelOptions, files: list[str], preset: str | None,
    error_model: str, load: Payload | None, method: str, declared: dict[str, float] | None,
    loss: str, limits: GateLimits, profile: str | None, bootstrap: int, n_jobs: int,
    force: bool, yes: bool, out: str, as_json: bool,
) -> None:  # fmt: skip
    """``calibrate`` on pose or instrument files: run the workflow, gate, write, print.

    ``declared``: the ``--noise`` 1σ ``{"position": mm, "orientation": mrad}`` or None;
    ``load``: the ``--payload``; the other arguments are the command's options.
    """
    from pincal.cli._gate import apply_gate, bootstrap_lines
    from pincal.cli._joint_terms import carrying, terms_texts
    from pincal.io import (
        CALIBRATED_SIDECAR,
        CALIBRATED_URDF,
        MANIFEST,
        MODEL_RECORD,
        write_calibration,
    )
    from pincal.model import split_model
    from pincal.report import calibration_text
    from pincal.workflow import (
        calibrate_instrument_files,
        calibrate_pose_file,
        pose_parameters,
        pose_problem,
        reduction_line,
    )

    terms = split_model(error_model)
    mech = carrying(load_model(model, model_opts), load)
    preset, params = pose_parameters(mech, preset, terms)
    for f in files:
        check_data_rows(f, "--data", len(params), yes)
    if is_instrument_file(files[0]):
        if declared is not None or loss != "linear":
            raise click.BadParameter(
                "an instrument file carries its own noise; --noise and --loss apply to "
                "pose measurement files",
                param_hint="--data",
            )
        run = calibrate_instrument_files(mech, params, files, method, force, limits, profile,
                                         bootstrap, n_jobs, _steps())  # fmt: skip
    else:
        problem = pose_problem(mech, params, files[0], limits, force)
        if problem.rank < len(params):
            click.echo(reduction_line(preset, problem.rank, len(params)), err=True)
        run = calibrate_pose_file(problem, method, declared, loss, profile, bootstrap, n_jobs,
                                  _steps())  # fmt: skip
    for note in run.notes:
        click.echo(f"pincal: note: {note}", err=True)
    quality = apply_gate(run.verdict, force)
    if run.uncertainty is not None:
        quality["uncertainty"] = run.uncertainty
    out_dir = Path(out)
    data = ", ".join(map(str, files))
    doc = result_json(run.result, data, CALIBRATED_URDF)
    doc["quality"] = quality
    report = calibration_text(run.result, {"data": data, "quality": quality})
    texts = {"report.txt": report}
    record = model_record(model, model_opts)  # the model with --sidecar/--frame/--lock
    if record is not None:
        texts[MODEL_RECORD] = record
    texts |= terms_texts(run.result, error_model, terms, load)
    source = MODEL_RECORD if record else model_source(model)  # relative: the directory moves
    cal = write_calibration(
        out_dir,
        run.result,
        model_source=source,
        data_files=files,
        noise=run.noise,
        annotations={"data": data, "quality": quality},
        texts=texts,
        nominal=mech if load is not None else None,  # the payload is part of the model
    )
    if terms:
        click.echo(f"pincal: note: the joint terms ({'+'.join(terms)}) are in joint_terms.yaml; "
                   "calibrated.urdf is the geometric part; compensate applies them, validate "
                   "not yet", err=True)  # fmt: skip
    if as_json:
        click.echo(json.dumps(doc))
    else:
        click.echo(report, nl=False)
        for line in bootstrap_lines(run.uncertainty):
            click.echo(line)
        click.echo(
            f"wrote calibration directory {cal.path}/ ({MANIFEST}, {CALIBRATED_URDF} + "
            f"{CALIBRATED_SIDECAR}, identification.json, report.txt)"
        )
