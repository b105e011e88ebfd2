"""`pincal poses`: choose measurement poses that maximise an observability index."""

from __future__ import annotations

import json

import click

from pincal.cli._limits import (
    MAX_POSES,
    MAX_RESTARTS,
    NOISE_RANGE,
    check_count,
    check_number,
    naming_option,
    yes_option,
)
from pincal.cli._pose_screens import screen_options
from pincal.cli.common import (
    ModelOptions,
    fail_cleanly,
    guard_paths,
    load_model,
    model_input,
    model_options,
    overwrite_option,
)
from pincal.measure import DEFAULT_NOISE


@click.command()
@click.argument("model")
@click.option("--count", default=18, show_default=True, help="Number of poses to select.")
@click.option(
    "--index",
    "index_name",
    type=click.Choice(["O1", "O2", "O3", "O4", "O5", "A"]),
    default="O1",
    show_default=True,
    help="Observability index to maximise.",
)
@click.option(
    "--candidates",
    "spec",
    default="grid:4",
    show_default=True,
    help="grid:LEVELS (joint grid), random:COUNT or oa:LEVELS (orthogonal array); "
    "more than 200000 candidate poses or ~2 GB need --yes.",
)
@click.option("--preset", default=None, help="Parameter preset (default: first, else full).")
@click.option(
    "--scaling",
    type=click.Choice(["noise", "K", "none"]),
    default="noise",
    show_default=True,
    help="Row scaling: noise whitening, Jzg with --K, or unscaled SI.",
)
@click.option("--K", "K_mm", type=float, default=None, help="Characteristic length [mm] (Jzg).")
@click.option("--noise", nargs=2, type=float,
              default=(DEFAULT_NOISE.position, DEFAULT_NOISE.orientation), show_default=True,
              help="Noise std: position [mm] orientation [mrad] (the default of every "
              "command).")  # fmt: skip
@click.option(
    "--method",
    type=click.Choice(["exchange", "detmax", "greedy"]),
    default="exchange",
    show_default=True,
)
@click.option(
    "--order",
    type=click.Choice(["travel", "selection"]),
    default="travel",
    show_default=True,
    help="Order of the poses in OUT: a short joint-space tour from home (nearest neighbour "
    "+ 2-opt; 1 rad/s, 0.1 m/s) or the selection's order.",
)
@click.option("--restarts", default=3, show_default=True, help="Random starts (best kept).")
@click.option("--seed", default=0, type=click.IntRange(min=0), show_default=True,
              help="Random seed.")  # fmt: skip
@click.option(
    "--out",
    default="poses.csv",
    show_default=True,
    help="Pose file to write (+ <stem>.commands.csv and <stem>.json beside it).",
)
@click.option(
    "--jobs",
    "n_jobs",
    type=click.IntRange(min=-1),
    default=1,
    show_default=True,
    help="Processes evaluating the candidates (-1: every CPU); same poses for any value.",
)
@click.option("--json", "as_json", is_flag=True, help="Print a JSON summary on stdout.")
@screen_options
@yes_option
@overwrite_option
@model_options
@fail_cleanly
def poses(
    model: str,
    count: int,
    index_name: str,
    spec: str,
    preset: str | None,
    scaling: str,
    K_mm: float | None,
    noise: tuple[float, float],
    method: str,
    order: str,
    restarts: int,
    seed: int,
    out: str,
    n_jobs: int,
    as_json: bool,
    joint_margin: float,
    singular_margin: float,
    obstacles: tuple[str, ...],
    no_collisions: bool,
    reach_errors: str,
    yes: bool,
    overwrite: bool,
    model_opts: ModelOptions,
) -> None:
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
    import dataclasses
    from pathlib import Path

    import numpy as np

    from pincal.cli._pose_screens import compensation_test, parse_reach_errors, screen_settings
    from pincal.cli._progress import counted
    from pincal.cli.info import reduction_line
    from pincal.design import (
        MAX_CANDIDATE_BYTES,
        MAX_CANDIDATES,
        DesignScaling,
        candidate_set,
        characteristic_length,
        cramer_rao_from_jacobian,
        parse_candidate_spec,
        screen_candidates,
        select_poses,
        travel_order,
    )
    from pincal.errors import OptionValueError, PincalError
    from pincal.io import si_actuator_units, write_pose_design
    from pincal.measure import NoiseModel
    from pincal.sensitivity import base_parameters, parameters

    guard_paths(
        {"MODEL": model_input(model)},
        {"--out": out},
        implied={"--out's commands file": Path(out).with_suffix(".commands.csv"),
                 "--out's JSON record": Path(out).with_suffix(".json")},
        overwrite=overwrite,
    )  # fmt: skip
    check_count(count, "--count", MAX_POSES, yes)
    n_jobs = _jobs(n_jobs)
    check_count(restarts, "--restarts", MAX_RESTARTS, yes, what="restarts")
    check_number(K_mm, "--K", positive=True)
    for value, name in zip(noise, ("--noise (position)", "--noise (orientation)"), strict=True):
        check_number(value, name, positive=True)
        if not NOISE_RANGE[0] <= value <= NOISE_RANGE[1]:
            raise OptionValueError(
                f"{name} {value:g} must be between {NOISE_RANGE[0]:g} and {NOISE_RANGE[1]:g} "
                "(mm, mrad)"
            )
    with naming_option("--candidates"):
        parse_candidate_spec(spec)  # a malformed spec fails before the model loads
    settings = screen_settings(joint_margin, singular_margin, obstacles, no_collisions)
    errors = parse_reach_errors(reach_errors)
    mech = load_model(model, model_opts)
    preset = preset or (next(iter(mech.presets)) if mech.presets else "full")
    params = parameters(mech, preset)
    preset_params = params  # the reach screen draws its errors on these
    reduced = base_parameters(mech, params)
    if len(reduced) < len(params):
        click.echo(reduction_line(preset, len(reduced), len(params)), err=True)
        params = reduced
    click.echo(f"{mech.name}: {len(params)} parameters (preset {preset!r})", err=True)
    with counted(f"candidates {spec}", unit="pose") as progress:
        with naming_option("--candidates"):
            cands = candidate_set(
                mech, params, spec, rng=seed, progress=progress,
                max_candidates=None if yes else MAX_CANDIDATES,
                max_bytes=None if yes else MAX_CANDIDATE_BYTES, n_jobs=n_jobs,
            )  # fmt: skip
    compensable = None if errors is None else compensation_test(mech, preset_params, errors, seed)
    cands, screens = screen_candidates(mech, cands, settings, compensable=compensable)
    click.echo(cands.summary(), err=True)
    click.echo(f"  {screens.summary()}", err=True)
    for note in screens.notes:
        click.echo(f"  {note}", err=True)
    if count > len(cands):
        raise OptionValueError(
            f"--count {count} is more than the {len(cands)} feasible candidate poses of "
            f"--candidates {spec} ({screens.summary()}); ask for at most {len(cands)} poses, "
            "generate more candidates (e.g. --candidates random:2000 or a finer "
            "grid:LEVELS) or relax the screens (--joint-margin, --singular-margin)"
        )
    noise_model = NoiseModel(*noise)
    if scaling == "K":
        K = (
            K_mm * 1e-3
            if K_mm is not None
            else characteristic_length(cands.jacobians, cands.components)
        )
        design_scaling = DesignScaling(rows="K", K=K)
    elif scaling == "noise":
        if K_mm is not None:
            raise PincalError("--K applies to --scaling K only")
        sig = noise_model.std(("x", "rx"))
        design_scaling = DesignScaling(
            rows="noise", position_std=float(sig[0]), orientation_std=float(sig[1])
        )
    else:
        design_scaling = DesignScaling(rows="none")
    click.echo(f"scaling: {design_scaling.describe()}", err=True)
    design = select_poses(
        cands, count, index_name, design_scaling, method, rng=np.random.default_rng(seed),
        restarts=restarts,
    )  # fmt: skip
    if order == "travel":
        speeds = [0.1 if mech.tree.joints[j].type == "prismatic" else 1.0 for j in mech.actuated]
        tour = travel_order(design.q_act, mech.actuators_of(mech.q_home), speeds)
        design = dataclasses.replace(
            design,
            candidates=design.candidates.subset(tour.order),
            indices=design.indices[tour.order],
        )
        click.echo(tour.summary(), err=True)
    crb = cramer_rao_from_jacobian(
        design.candidates.jacobians, cands.components, noise_model, None,
        params.names, params.units,
    )  # fmt: skip
    extra = {
        "noise": {"position_mm": noise[0], "orientation_mrad": noise[1]},
        "predicted_std": dict(zip(params.names, map(float, crb.std), strict=True)),
        "screens": {"removed": screens.removed, "notes": list(screens.notes),
                    "reach_errors_mm_mrad": None if errors is None else list(errors)},
    }  # fmt: skip
    csv_path, cmd_path, json_path = write_pose_design(
        design, out, extra, actuator_units=si_actuator_units(mech)
    )
    sel = design.selection
    if as_json:
        click.echo(
            json.dumps(
                {
                    "model": mech.name,
                    "preset": preset,
                    "poses": str(csv_path),
                    "commands": str(cmd_path),
                    "design": str(json_path),
                    "count": len(design.candidates),
                    "index": index_name,
                    "value": float(sel.value),
                    "converged": bool(sel.converged),
                    "predicted_rms_std": float(crb.rms_std),
                    "screens_removed": screens.removed,
                }
            )
        )
        return
    hist = " → ".join(f"{v:.5g}" for v in (sel.history[0], sel.history[-1]))
    click.echo(
        f"{method}: {index_name} {hist} in {sel.iterations} iterations "
        f"({'converged' if sel.converged else 'iteration limit'}); "
        f"condition number {design.indices_all.condition_number:.4g}"
    )
    click.echo(crb.summary())
    click.echo(
        f"wrote {csv_path} ({len(design.candidates)} nominal poses with their actuator "
        f"values), {cmd_path} and {json_path}"
    )


def _jobs(n_jobs: int) -> int:
    """``--jobs`` checked and clamped to the CPU count (more processes only compete)."""
    import os

    from pincal.errors import OptionValueError

    cpus = os.cpu_count() or 1
    if n_jobs == 0:
        raise OptionValueError(
            f"--jobs 0 is not valid; give a number of processes from 1 to {cpus} (the CPU "
            "count), or -1 for every CPU"
        )
    if n_jobs > cpus:
        click.echo(f"pincal: note: --jobs {n_jobs} is more than the {cpus} CPUs; using {cpus}",
                   err=True)  # fmt: skip
        return cpus
    return n_jobs
