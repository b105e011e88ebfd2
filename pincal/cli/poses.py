"""`pincal poses`: choose measurement poses that maximise an observability index."""

from __future__ import annotations

import json

import click

from pincal.cli._limits import (
    MAX_POSES,
    MAX_RESTARTS,
    check_count,
    check_number,
    naming_option,
    yes_option,
)
from pincal.cli._paths import guard_paths, overwrite_option
from pincal.cli._pose_options import check_noise, jobs, pose_options
from pincal.cli._pose_screens import screen_options
from pincal.cli.common import ModelOptions, fail_cleanly, load_model, model_input, model_options


@click.command()
@click.argument("model")
@pose_options
@screen_options
@yes_option
@overwrite_option
@model_options
@fail_cleanly
def poses(
    model: str, count: int, index_name: str, spec: str, preset: str | None, scaling: str,
    K_mm: float | None, noise: tuple[float, float], method: str, order: str, restarts: int,
    seed: int, out: str, n_jobs: int, scheduler: str | None, as_json: bool, joint_margin: float,
    singular_margin: float, obstacles: tuple[str, ...], no_collisions: bool, reach_errors: str,
    yes: bool, overwrite: bool, model_opts: ModelOptions,
) -> None:  # fmt: skip
    """Select measurement poses of MODEL from a candidate set and write them to OUT.

    OUT is a pincal pose file: the nominal measured-frame poses (x y z [mm], rotation
    vector rx ry rz [mrad]) and the actuator values of each pose (columns named after
    the actuated joints, unit in brackets). `pincal view --poses`, `simulate --poses`
    and `compensate --targets` read it as it is. <stem>.commands.csv repeats the
    actuator values alone; <stem>.json gets the index history, all indices, the
    scaling and the Cramér–Rao prediction.

    \b
    Examples:
      pincal poses hexaslide_6pus --count 40 --candidates random:300 --out poses.csv
      pincal poses stewart_6ups --count 18 --index O3 --scaling K --out p.csv --json
    """
    from pathlib import Path

    from pincal.cli._pose_screens import parse_reach_errors, screen_settings
    from pincal.cli._progress import counted
    from pincal.design import MAX_CANDIDATE_BYTES, MAX_CANDIDATES, parse_candidate_spec
    from pincal.executor import parse_scheduler
    from pincal.io import si_actuator_units, write_pose_design
    from pincal.workflow import PoseRequest, pose_basis, pose_candidates, select_pose_design

    guard_paths(
        {"MODEL": model_input(model)},
        {"--out": out},
        implied={"--out's commands file": Path(out).with_suffix(".commands.csv"),
                 "--out's JSON record": Path(out).with_suffix(".json")},
        overwrite=overwrite,
    )  # fmt: skip
    check_count(count, "--count", MAX_POSES, yes)
    n_jobs = jobs(n_jobs)
    check_count(restarts, "--restarts", MAX_RESTARTS, yes, what="restarts")
    check_number(K_mm, "--K", positive=True)
    check_noise(noise)
    with naming_option("--candidates"):
        parse_candidate_spec(spec)  # a malformed spec fails before the model loads
    with naming_option("--scheduler:"):
        parse_scheduler(scheduler, n_jobs)
    settings = screen_settings(joint_margin, singular_margin, obstacles, no_collisions)
    errors = parse_reach_errors(reach_errors)
    mech = load_model(model, model_opts)
    basis = pose_basis(mech, preset)
    for line in basis.lines(mech.name):
        click.echo(line, err=True)
    with counted(f"candidates {spec}", unit="pose") as progress:
        with naming_option("--candidates"):
            cands = pose_candidates(
                mech, basis, spec, seed, max_candidates=None if yes else MAX_CANDIDATES,
                max_bytes=None if yes else MAX_CANDIDATE_BYTES, n_jobs=n_jobs, progress=progress,
                scheduler=scheduler, screens=settings,
            )  # fmt: skip
    request = PoseRequest(count, index_name, scaling, K_mm, noise, method, order, restarts, seed,
                          errors, spec)  # fmt: skip
    chosen = select_pose_design(mech, basis, cands, request, settings,
                                say=lambda line: click.echo(line, err=True))  # fmt: skip
    csv_path, cmd_path, json_path = write_pose_design(
        chosen.design, out, chosen.extra, actuator_units=si_actuator_units(mech)
    )
    if as_json:
        click.echo(json.dumps({"model": mech.name, "preset": basis.preset, "poses": str(csv_path),
                               "commands": str(cmd_path), "design": str(json_path),
                               **chosen.record()}))  # fmt: skip
        return
    for line in chosen.lines():
        click.echo(line)
    click.echo(
        f"wrote {csv_path} ({len(chosen.design.candidates)} nominal poses with their actuator "
        f"values), {cmd_path} and {json_path}"
    )
