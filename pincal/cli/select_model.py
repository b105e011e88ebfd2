"""``pincal select-model``: rank error models by K-fold cross-validated held-out error."""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import TYPE_CHECKING

import click

from pincal.cli._joint_terms import carrying, payload_option, read_payload
from pincal.cli._markers import marker_options
from pincal.cli.common import (
    ModelOptions,
    fail_cleanly,
    guard_paths,
    load_model,
    model_input,
    model_options,
)

if TYPE_CHECKING:  # imported in the calls: the CLI starts without the identification stack
    from pincal.identification import Fitted
    from pincal.measure import MarkerSetup, Measurements
    from pincal.model import Mechanism

    #: a candidate fitting procedure: training measurements → predictor
    _Procedure = Callable[[Measurements], Fitted]

__all__ = ["select_model_cmd"]

DEFAULT_MODELS = (
    "geometric,geometric+compliance,geometric+gain,geometric+harmonics,"
    "geometric+compliance+gain+harmonics"
)


def _pose_candidates(
    mech: Mechanism, meas: Measurements, preset: str, models: list[str], method: str
) -> dict[str, _Procedure]:
    from pincal.identification import fitted, identify
    from pincal.model import split_model
    from pincal.sensitivity import parameters

    def make(spec: str) -> _Procedure:
        params = parameters(mech, "+".join([preset, *split_model(spec)]))
        return lambda m: fitted(mech, identify(mech, params, m, method))

    return {spec: make(spec) for spec in models}


def _marker_candidates(
    mech: Mechanism, setup: MarkerSetup, preset: str, models: list[str], method: str
) -> dict[str, _Procedure]:
    from pincal.identification import fit_markers, fitted
    from pincal.model import split_model

    def make(spec: str) -> _Procedure:
        full = "+".join([preset, *split_model(spec)])

        def fit(m: Measurements) -> Fitted:
            f = fit_markers(mech, setup, m, full, method)
            return fitted(f.registration.mechanism, f.result)

        return fit

    def registration(m: Measurements) -> Fitted:
        f = fit_markers(mech, setup, m, registration_only=True)
        return fitted(f.registration.mechanism, f.result)

    return {"registration only": registration, **{spec: make(spec) for spec in models}}


@click.command("select-model")
@click.argument("model")
@click.option(
    "--data",
    required=True,
    type=click.Path(dir_okay=False),
    help="Measurement file (pose file, or a marker table with --link).",
)
@click.option(
    "--params",
    "preset",
    default=None,
    help="Geometric preset of every candidate (default: the model's first; chain with --link).",
)
@click.option(
    "--models",
    default=DEFAULT_MODELS,
    show_default=True,
    help="Comma-separated candidate error models (geometric[+TERM…]).",
)
@click.option(
    "--cv", "k", type=click.IntRange(2, 100), default=5, show_default=True, help="Number of folds."
)
@click.option(
    "--seed",
    type=click.IntRange(0, 2**32 - 1),
    default=0,
    show_default=True,
    help="Seed of the folds.",
)
@click.option(
    "--method",
    type=click.Choice(["gauss-newton", "lm"]),
    default="gauss-newton",
    show_default=True,
    help="Identification solver of every fit.",
)
@payload_option("Payload on the tool during the measurements (kg; centre of mass in m in the "
                "tool frame), e.g. 20,0,0,0.1: part of the load a compliance term sees.")
@click.option("--json", "as_json", is_flag=True, help="Print the ranking as JSON on stdout.")
@model_options
@marker_options
@fail_cleanly
def select_model_cmd(
    model: str,
    data: str,
    preset: str | None,
    models: str,
    k: int,
    seed: int,
    method: str,
    payload: str | None,
    as_json: bool,
    model_opts: ModelOptions,
    link: str | None,
    instrument_frame: str,
    marker_spec: str,
    marker_columns: tuple[str, ...],
    length_unit: str,
    orientation_columns: str | None,
    orientation: str | None,
    prior_spec: str | None,
) -> None:
    """Fit candidate error models and rank them by K-fold held-out position error.

    Every candidate is refitted from scratch on each fold (for a marker table the
    closed-form registration too) and predicts the held-out poses with its joint terms
    applied; the standard errors are those of the paired per-pose differences to the
    best. The recommendation is the smallest model within one standard error of the
    best: a term that does not lower the held-out error by more than its scatter does
    not pay. A marker table adds the registration-only model (the robot uncalibrated).

    \b
    Examples:
      pincal select-model ur5 --data m.csv --params base
      pincal select-model tiago --link arm_7_link --data mocap.csv \\
          --marker-columns x1,y1,z1 --models geometric,geometric+compliance
    """
    from pincal.identification import select_model
    from pincal.model import split_model

    guard_paths({"MODEL": model_input(model), "--data": data, "--sidecar": model_opts.sidecar})
    specs = [s.strip() for s in models.split(",") if s.strip()]
    if not specs:
        raise click.BadParameter("give at least one model", param_hint="--models")
    for s in specs:
        split_model(s)
    load = read_payload(payload)
    if link is not None and load is not None:
        raise click.BadParameter("a payload is not used with a marker table (--link) yet",
                                 param_hint="--payload")  # fmt: skip
    if link is not None:
        from pincal.cli._markers import setup_from_options
        from pincal.io import read_marker_table
        from pincal.measure import marker_mechanism

        if prior_spec is not None:
            raise click.BadParameter("a prior is not used in model selection (not yet)",
                                     param_hint="--prior")  # fmt: skip
        if orientation_columns is not None or orientation is not None:
            raise click.BadParameter("model selection ranks by held-out positions; a marker "
                                     "body's orientation is not used there (not yet): leave "
                                     "out --orientation-columns",
                                     param_hint="--orientation-columns")  # fmt: skip
        lock_spec = ",".join(f"{a}={v!r}" for a, v in model_opts.lock.items()) or None
        setup = setup_from_options(link, instrument_frame, marker_spec, marker_columns,
                                   length_unit, lock_spec)  # fmt: skip
        mech = marker_mechanism(model, setup)
        meas = read_marker_table(data, mech, setup)
        candidates = _marker_candidates(mech, setup, preset or "chain", specs, method)
    else:
        from pincal.io import read_measurement_file

        mech = carrying(load_model(model, model_opts), load)
        meas = read_measurement_file(data, mech).measurements
        candidates = _pose_candidates(mech, meas, preset or next(iter(mech.presets), "full"),
                                      specs, method)  # fmt: skip
    click.echo(f"… {len(candidates)} models × {k} folds on {len(meas)} poses", err=True)
    sel = select_model(candidates, meas, k, seed)
    if as_json:
        click.echo(json.dumps(sel.to_dict()))
    else:
        for line in sel.lines():
            click.echo(line)
