"""``pincal select-model``: rank error models by K-fold cross-validated held-out error."""

from __future__ import annotations

import json

import click

from pincal.cli._joint_terms import carrying, payload_option, read_payload
from pincal.cli._limits import check_data_rows, yes_option
from pincal.cli._markers import marker_table_options
from pincal.cli._paths import guard_paths
from pincal.cli.common import ModelOptions, fail_cleanly, load_model, model_input, model_options

__all__ = ["select_model_cmd"]

DEFAULT_MODELS = (
    "geometric,geometric+compliance,geometric+gain,geometric+harmonics,"
    "geometric+compliance+gain+harmonics"
)


@click.command("select-model")
@click.argument("model")
@click.option("--data", required=True, type=click.Path(dir_okay=False),
              help="Measurement file (pose file, or a marker table with --link).")  # fmt: skip
@click.option("--params", "preset", default=None, help="Geometric preset of every candidate "
              "(default: the model's first; chain with --link).")  # fmt: skip
@click.option("--models", default=DEFAULT_MODELS, show_default=True,
              help="Comma-separated candidate error models (geometric[+TERM…]).")  # fmt: skip
@click.option("--cv", "k", type=click.IntRange(2, 100), default=5, show_default=True,
              help="Number of folds.")  # fmt: skip
@click.option("--seed", type=click.IntRange(0, 2**32 - 1), default=0, show_default=True,
              help="Seed of the folds.")  # fmt: skip
@click.option("--method", type=click.Choice(["gauss-newton", "lm"]), default="gauss-newton",
              show_default=True, help="Identification solver of every fit.")  # fmt: skip
@payload_option("Payload on the tool during the measurements (kg; centre of mass in m in the "
                "tool frame), e.g. 20,0,0,0.1: part of the load a compliance term sees.")
@click.option("--json", "as_json", is_flag=True, help="Print the ranking as JSON on stdout.")
@yes_option
@model_options
@marker_table_options
@fail_cleanly
def select_model_cmd(
    model: str, data: str, preset: str | None, models: str, k: int, seed: int, method: str,
    payload: str | None, as_json: bool, yes: bool, model_opts: ModelOptions, link: str | None,
    instrument_frame: str, marker_spec: str, marker_columns: tuple[str, ...], length_unit: str,
) -> None:  # fmt: skip
    """Fit candidate error models and rank them by K-fold held-out position error.

    Every candidate is refitted from scratch on each fold (for a marker table the
    closed-form registration too) and predicts the held-out poses with its joint terms
    applied; the standard errors are those of the paired per-pose differences to the
    best. The recommendation is the smallest model within one standard error of the
    best: a term that does not lower the held-out error by more than its scatter does
    not pay. A marker table adds the registration-only model (the robot uncalibrated).
    Of the default list, a model whose terms the machine cannot take (compliance
    without link masses, harmonics on a prismatic actuator) is left out and said.

    \b
    Examples:
      pincal select-model ur5 --data m.csv --params base
      pincal select-model tiago --link arm_7_link --data mocap.csv \\
          --marker-columns x1,y1,z1 --models geometric,geometric+compliance
    """
    from pincal.model import split_model
    from pincal.workflow import select_marker_model, select_pose_model

    guard_paths({"MODEL": model_input(model), "--data": data, "--sidecar": model_opts.sidecar})
    check_data_rows(data, "--data", 0, yes)  # every candidate is fitted k + 1 times
    specs = [s.strip() for s in models.split(",") if s.strip()]
    if not specs:
        raise click.BadParameter("give at least one model", param_hint="--models")
    for s in specs:
        split_model(s)
    load = read_payload(payload)
    if link is not None and load is not None:
        raise click.BadParameter("a payload is not used with a marker table (--link) yet",
                                 param_hint="--payload")  # fmt: skip
    say = lambda line: click.echo(f"… {line}", err=True)  # noqa: E731
    default = models == DEFAULT_MODELS  # the default list: leave out what does not apply
    if link is not None:
        from pincal.cli._markers import setup_from_options

        lock_spec = ",".join(f"{a}={v!r}" for a, v in model_opts.lock.items()) or None
        setup = setup_from_options(link, instrument_frame, marker_spec, marker_columns,
                                   length_unit, lock_spec)  # fmt: skip
        sel = select_marker_model(model, data, setup, preset, specs, method, k, seed, say,
                                  default)  # fmt: skip
    else:
        mech = carrying(load_model(model, model_opts), load)
        sel = select_pose_model(mech, data, preset, specs, method, k, seed, say, default)
    if as_json:
        click.echo(json.dumps(sel.to_dict()))
    else:
        for line in sel.lines():
            click.echo(line)
