"""A pose measurement file calibrated as ``pincal calibrate --data FILE`` does it.

:func:`pose_parameters` settles the preset and the parameters (joint terms included);
:func:`pose_problem` reads the file, lets the quality gate look at the data (a
refusal stops before the fit) and finds how many parameters the model's measured
components identify; :func:`calibrate_pose_file` fits them, judges the fit
(:func:`pincal.identification.check_quality`), checks the fit's linearisation (its σ
inflated where it fails) and returns everything a report or a calibration directory
needs as one :class:`PoseRun`. Instrument files go through
:func:`pincal.workflow.calibrate_instrument_files` instead. Nothing is written.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pincal.errors import QualityGateError
from pincal.identification import (
    GateLimits,
    GaussNewtonOptions,
    IdentificationResult,
    LMOptions,
    QualityVerdict,
    check_quality,
    check_uncertainty,
    identify,
    pose_recipe,
    pose_residual_model,
    with_uncertainty,
)
from pincal.io import check_enough_poses, read_measurement_file
from pincal.measure import Measurements, NoiseModel
from pincal.model import Mechanism, ParameterSet, check_term_data, with_joint_terms
from pincal.sensitivity import identifiability, parameters
from pincal.workflow._steps import Steps

__all__ = ["PoseProblem", "PoseRun", "calibrate_pose_file", "pose_parameters", "pose_problem"]


@dataclass(frozen=True)
class PoseRun:
    """A calibration from measurement files, as the workflow ran it.

    Returned by :func:`calibrate_pose_file` and
    :func:`pincal.workflow.calibrate_instrument_files`.

    Attributes:
        result: the fit, its covariance the honest one (the linear one inflated along
            the directions found non-linear) when the check ran.
        verdict: the quality gate's verdict on the fit (not yet applied: a refusal is
            the caller's to raise or override).
        uncertainty: the uncertainty check's JSON summary (``quality.uncertainty``),
            None when it did not run (a robust loss, a refused fit).
        noise: the pose file's declared noise model (None: none, or instrument files).
        notes: what was decided or skipped, in words.
    """

    result: IdentificationResult
    verdict: QualityVerdict
    uncertainty: dict[str, object] | None
    noise: NoiseModel | None = None
    notes: tuple[str, ...] = ()


@dataclass(frozen=True)
class PoseProblem:
    """A pose file read and looked at, before the fit (see :func:`pose_problem`).

    Attributes:
        mech: the model (with its payload).
        params: the parameters to identify (n of them).
        meas: the measured poses.
        rank: how many of the n parameters the measured components identify (the
            structural rank); fewer than n: the preset is reduced to a base set.
        data: the gate's verdict on the data, with the caller's limits.
        instrument: the file's ``# instrument:`` profile name, or None.
    """

    mech: Mechanism
    params: ParameterSet
    meas: Measurements
    rank: int
    data: QualityVerdict
    instrument: str | None


def _loss_options(method: str, loss: str) -> GaussNewtonOptions | LMOptions | None:
    """The local solver's options carrying ``loss`` (None: the method's defaults)."""
    if method == "lm":
        return LMOptions(loss=loss)
    return GaussNewtonOptions(loss=loss) if method == "gauss-newton" and loss != "linear" else None


def pose_parameters(
    mech: Mechanism, preset: str | None, terms: tuple[str, ...] | list[str]
) -> tuple[str, ParameterSet]:
    """The preset (None: the model's first, else ``full``) and its parameters.

    Args:
        mech: the model.
        preset: a preset name of ``mech``, or None.
        terms: joint-space terms identified beside the geometric parameters
            (:func:`pincal.model.split_model`'s).

    Returns:
        (the preset's name, its parameters [m, rad] with the terms' appended).
    """
    name = preset or next(iter(mech.presets), "full")
    return name, with_joint_terms(mech, parameters(mech, name), terms)


def pose_problem(
    mech: Mechanism, params: ParameterSet, data: str | Path, limits: GateLimits, force: bool
) -> PoseProblem:
    """Read the pose file, gate its data, find the structural rank (see :class:`PoseProblem`).

    Args:
        mech: the model the file must use (actuated joints, measured frame).
        params: the parameters to identify.
        data: the pose / position / target measurement file.
        limits: the quality gate's limits.
        force: a refusal of the data is recorded, not raised (``--force``).

    Raises:
        QualityGateError: the data are refused (unit mistake, …) and ``force`` is False.
        TooFewPosesError: fewer poses than identifiable parameters.
        PincalError subclasses of reading the file (and of a thermal term's data).
    """
    mf = read_measurement_file(data, mech)  # its data check is the gate's first look
    meas = mf.measurements
    gate = dataclasses.replace(mf.data_check, limits=limits)
    if not gate.passed and not force:
        raise QualityGateError(gate.reason(), gate)
    if "1/K" in params.units:  # a thermal term: its rank depends on the data's temperatures
        check_term_data(params, meas.conditions)
        structural = identifiability(mech, params, meas.q_act, conditions=meas.conditions)
    else:
        structural = identifiability(mech, params, rng=np.random.default_rng(0))
    check_enough_poses(meas, structural.rank)
    return PoseProblem(mech, params, meas, structural.rank, gate, mf.instrument)


def calibrate_pose_file(
    problem: PoseProblem,
    method: str,
    declared: dict[str, float] | None = None,
    loss: str = "linear",
    profile: str | None = None,
    bootstrap: int = 0,
    n_jobs: int = 1,
    steps: Steps | None = None,
) -> PoseRun:
    """Fit, judge and check the σ of a pose-file calibration (see :class:`PoseRun`).

    Args:
        problem: the file read (:func:`pose_problem`).
        method: the identification solver (:data:`pincal.identification.METHODS`).
        declared: the noise 1σ ``{"position": mm, "orientation": mrad}`` given for the
            file (overriding its header), or None.
        loss: ``linear`` or a robust loss (``method`` ``gauss-newton`` or ``lm``).
        profile: the instrument profile judging an estimated noise (None: the file's).
        bootstrap: parametric-bootstrap refits reported beside the σ (0: none; run on a
            passed least-squares fit only).
        n_jobs: processes of the refits (-1: every CPU).
        steps: progress callbacks (default: none).
    """
    steps = steps or Steps()
    meas = problem.meas
    steps.say(f"identifying {problem.rank} of {len(problem.params)} parameters from "
              f"{len(meas)} poses")  # fmt: skip
    with steps.iterations("identifying") as step:
        result = identify(problem.mech, problem.params, meas, method=method, progress=step,
                          noise=declared,
                          options=_loss_options(method, loss))  # fmt: skip
    verdict = check_quality(result, meas, mech=problem.mech, data=problem.data,
                            instrument=profile or problem.instrument)  # fmt: skip
    if loss != "linear" or not verdict.passed or not result.identified.any():
        notes = ("--bootstrap runs on a passed least-squares fit only (not with a robust "
                 "--loss or a refused fit); no refits ran",) if bootstrap else ()  # fmt: skip
        return PoseRun(result, verdict, None, meas.noise, notes)
    residuals = pose_residual_model(result, problem.mech, meas, declared)
    if residuals is None:
        return PoseRun(result, verdict, None, meas.noise)
    factory = pose_recipe(result, problem.mech, meas, declared) if bootstrap else None
    with steps.counted("bootstrap refits") as step:
        check = check_uncertainty(residuals, result,
                                  declared=verdict.noise_source in ("declared", "per-pose"),
                                  bootstrap=bootstrap, progress=step, n_jobs=n_jobs,
                                  factory=factory)  # fmt: skip
    return PoseRun(check.result, with_uncertainty(verdict, check), check.to_dict(), meas.noise)
