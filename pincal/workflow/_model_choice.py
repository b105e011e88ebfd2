"""Error models ranked as ``pincal select-model`` does it, without the CLI.

Every candidate error model (``geometric[+TERM…]``) is a procedure — training
measurements → a fitted predictor — refitted from scratch on each of K folds
(:func:`pincal.validation.select_model`); for a marker table the closed-form
registration is refitted too, and the registration alone is a candidate (the robot
uncalibrated). :func:`select_pose_model` and :func:`select_marker_model` read the data,
build the candidates and rank them. Nothing is written.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from pincal.errors import ParameterError
from pincal.identification import fit_markers, identify
from pincal.io import read_marker_table, read_measurement_file
from pincal.measure import MarkerSetup, Measurements, marker_mechanism
from pincal.model import Mechanism, split_model
from pincal.sensitivity import parameters
from pincal.validation import Fitted, ModelSelection, fitted, select_model

__all__ = ["select_marker_model", "select_pose_model"]

#: a candidate fitting procedure: training measurements → predictor
Procedure = Callable[[Measurements], Fitted]


def _applicable(
    mech: Mechanism,
    preset: str,
    models: list[str],
    skip: bool,
    progress: Callable[[str], None] | None,
) -> list[str]:
    """The candidate models whose parameters ``mech`` has.

    With ``skip`` an inapplicable one (a compliance term on a model without link
    masses…) is left out and said through ``progress``; else its error is raised.

    Raises:
        ParameterError: a model that does not apply (``skip`` False), or none applies.
    """
    kept = []
    for spec in models:
        try:
            parameters(mech, "+".join([preset, *split_model(spec)]))
        except ParameterError as exc:
            if not skip:
                raise
            if progress is not None:
                progress(f"left out {spec}: {exc}")
            continue
        kept.append(spec)
    if not kept:
        raise ParameterError(f"none of the models {', '.join(models)} applies to {mech.name!r}")
    return kept


def _pose_candidates(
    mech: Mechanism, preset: str, models: list[str], method: str
) -> dict[str, Procedure]:
    def make(spec: str) -> Procedure:
        params = parameters(mech, "+".join([preset, *split_model(spec)]))
        return lambda m: fitted(mech, identify(mech, params, m, method))

    return {spec: make(spec) for spec in models}


def _marker_candidates(
    mech: Mechanism, setup: MarkerSetup, preset: str, models: list[str], method: str
) -> dict[str, Procedure]:
    def make(spec: str) -> Procedure:
        full = "+".join([preset, *split_model(spec)])

        def fit(m: Measurements) -> Fitted:
            f = fit_markers(mech, setup, m, full, method)
            return fitted(f.registration.mechanism, f.result)

        return fit

    def registration(m: Measurements) -> Fitted:
        f = fit_markers(mech, setup, m, registration_only=True)
        return fitted(f.registration.mechanism, f.result)

    return {"registration only": registration, **{spec: make(spec) for spec in models}}


def _rank(
    candidates: dict[str, Procedure],
    meas: Measurements,
    k: int,
    seed: int,
    progress: Callable[[str], None] | None,
) -> ModelSelection:
    if progress is not None:
        progress(f"{len(candidates)} models × {k} folds on {len(meas)} poses")
    return select_model(candidates, meas, k, seed)


def select_pose_model(
    mech: Mechanism,
    data: str | Path,
    preset: str | None,
    models: list[str],
    method: str = "gauss-newton",
    k: int = 5,
    seed: int = 0,
    progress: Callable[[str], None] | None = None,
    skip_inapplicable: bool = False,
) -> ModelSelection:
    """Rank error models on a pose measurement file by K-fold held-out position error.

    Args:
        mech: the model (with its payload).
        data: the pose measurement file.
        preset: the geometric preset of every candidate (None: the model's first, else
            ``full``).
        models: the candidate error models, ``geometric[+TERM…]`` each.
        method: the identification solver of every fit.
        k: the number of folds.
        seed: the seed of the folds.
        progress: called with a line before the long step.
        skip_inapplicable: leave out (and say) a model whose terms ``mech`` cannot
            take, e.g. a compliance without link masses (the default list), instead
            of raising.

    Returns:
        The ranking (:class:`pincal.validation.ModelSelection`).

    Raises:
        ParameterError: a model does not apply (see ``skip_inapplicable``).
    """
    meas = read_measurement_file(data, mech).measurements
    preset = preset or next(iter(mech.presets), "full")
    models = _applicable(mech, preset, models, skip_inapplicable, progress)
    candidates = _pose_candidates(mech, preset, models, method)
    return _rank(candidates, meas, k, seed, progress)


def select_marker_model(
    model: str,
    data: str | Path,
    setup: MarkerSetup,
    preset: str | None,
    models: list[str],
    method: str = "gauss-newton",
    k: int = 5,
    seed: int = 0,
    progress: Callable[[str], None] | None = None,
    skip_inapplicable: bool = False,
) -> ModelSelection:
    """Rank error models on a marker table, the registration alone among them.

    Args:
        model: model name or file (as :func:`pincal.measure.marker_mechanism` takes it).
        data: the marker table.
        setup: what is measured and known (link, columns, instrument frame, marker).
        preset: the geometric preset of every candidate (None: ``chain``).
        models: the candidate error models, ``geometric[+TERM…]`` each.
        method: the identification solver of every fit.
        k: the number of folds.
        seed: the seed of the folds.
        progress: called with a line before the long step.
        skip_inapplicable: as :func:`select_pose_model`.

    Returns:
        The ranking (:class:`pincal.validation.ModelSelection`).

    Raises:
        ParameterError: a model does not apply (see ``skip_inapplicable``).
    """
    mech = marker_mechanism(model, setup)
    meas = read_marker_table(data, mech, setup)
    models = _applicable(mech, preset or "chain", models, skip_inapplicable, progress)
    candidates = _marker_candidates(mech, setup, preset or "chain", models, method)
    return _rank(candidates, meas, k, seed, progress)
