"""A marker table calibrated as ``pincal calibrate --link`` does it, without the CLI.

:func:`calibrate_markers` reads the table, registers the instrument frame and the
marker(s) in closed form, settles the prior and the loss (:class:`MarkerSettings`),
fits the machine with them, judges the fit (:func:`pincal.identification.check_quality`,
then :func:`pincal.validation.held_out_verdict`: with the noise estimated, K-fold
held-out prediction against the registration alone decides, the prior's choice redone
inside every fold when it was chosen) and returns everything a
report or a calibration directory needs as one :class:`MarkerRun`. Nothing is written.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from pincal.errors import TooFewPosesError, UnknownNameError
from pincal.identification import (
    MarkerFit,
    Prior,
    QualityIssue,
    QualityVerdict,
    check_quality,
    fit_markers,
    is_registration,
    stacked_measurements,
)
from pincal.io import distinct_markers, read_marker_data
from pincal.measure import MarkerSetup, Measurements, marker_mechanism
from pincal.model import Mechanism
from pincal.sensitivity import parameters
from pincal.validation import HeldOutEvidence, cross_validate, held_out_verdict
from pincal.workflow._marker_settings import MarkerSettings, parse_prior
from pincal.workflow._prior_choice import (
    PriorChoice,
    choose_prior,
    cross_validated,
    nested_choice,
)
from pincal.workflow._registrations import MarkerData, MarkerProcedure, Registrations

__all__ = [
    "MISFIT_RMS",
    "ROBUST_LOSS",
    "MarkerRun",
    "calibrate_markers",
    "marker_procedure",
    "registration_procedure",
]

#: registration RMS [m] beyond which the table does not describe the nominal robot
MISFIT_RMS = 0.02
#: registration RMS rotation angle [rad] of a marker body beyond which likewise (3°)
MISFIT_ANGLE = 0.05
#: the loss ``loss="auto"`` refits with when the outlier test names poses
ROBUST_LOSS = "huber"

Progress = Callable[[str], None]


@dataclass(frozen=True)
class MarkerRun:
    """A marker calibration as :func:`calibrate_markers` ran it.

    Attributes:
        fit: the fit (:class:`pincal.identification.MarkerFit`).
        meas: one measurement set per marker (copies of one marker left out).
        setup: the marker set-up fitted (copies left out).
        settings: the settings asked for.
        loss: the loss used (``settings.loss`` settled).
        choice: the prior used, with the held-out error of the procedure.
        verdict: the quality gate's verdict (judged by held-out prediction).
        notes: what was left out or decided, in words.
        warnings: findings worth a warning that the verdict does not hold.
        held_out: the cross-validation that judged the fit (the procedure's and the
            registration's, same folds), None when only the registration is fitted;
            recorded whole so that ``validate --cv`` with the same folds reuses it.
    """

    fit: MarkerFit
    meas: tuple[Measurements, ...]
    setup: MarkerSetup
    settings: MarkerSettings
    loss: str
    choice: PriorChoice
    verdict: QualityVerdict
    notes: tuple[str, ...]
    warnings: tuple[str, ...] = ()
    held_out: HeldOutEvidence | None = None

    @property
    def prior(self) -> Prior | None:
        """The prior the fit used (None: none)."""
        return self.choice.prior


def marker_procedure(
    mech: Mechanism,
    setup: MarkerSetup,
    preset: str,
    method: str,
    loss: str,
    registrations: Registrations | None = None,
) -> Callable[[Prior | None], MarkerProcedure]:
    """Prior → (measurements → calibrated mechanism): the fit that is cross-validated.

    ``registrations``: the registrations shared with other procedures of the same
    calibration (a new one when None): each set of poses is registered once.
    """
    reg = registrations or Registrations(mech, setup)

    def with_prior(prior: Prior | None) -> MarkerProcedure:
        def fit(meas: MarkerData) -> Mechanism:
            return fit_markers(mech, setup, meas, preset, method, prior, loss=loss,
                               registration=reg(meas)).calibrated  # fmt: skip

        return fit

    return with_prior


def registration_procedure(
    mech: Mechanism, setup: MarkerSetup, registrations: Registrations | None = None
) -> MarkerProcedure:
    """Measurements → the registration-only model (the baseline of a marker calibration)."""
    reg = registrations or Registrations(mech, setup)

    def fit(meas: MarkerData) -> Mechanism:
        return fit_markers(mech, setup, meas, registration_only=True,
                           registration=reg(meas)).calibrated  # fmt: skip

    return fit


def _misfit_note(rms: float) -> str:
    return (
        f"the registration leaves {rms * 1e3:.3g} mm RMS, more than {MISFIT_RMS * 1e3:g} mm: "
        "a nominal robot seen by a capture system fits to millimetres, so the table and the "
        "model disagree — check the joint columns (mapping, unit, reference pose: columns, "
        "joint_units, joint_reference), the joints locked and their values, the marker's link "
        "and the marker columns' unit"
    )


def _angle_note(rms: float) -> str:
    return (
        f"the registration leaves a rotation angle RMS of {rms * 1e3:.3g} mrad, more than "
        f"{MISFIT_ANGLE * 1e3:g} mrad: a nominal robot seen by a capture system fits to "
        "milliradians, so the orientation columns and the model disagree — check their "
        "convention, order and unit (--orientation: rpy-deg, quat-wxyz, …) and that the body "
        "is on the marker's link"
    )


def _leave_one_out_note(sizes: list[int], k: int) -> str:
    poses = "–".join(map(str, sorted({min(sizes), max(sizes)})))
    return (
        f"the prior of {len(sizes)} of the {k} cross-validation folds was chosen by "
        f"leave-one-out: their {poses} training poses are too few for an inner {k}-fold "
        "split to fit"
    )


def _gate(
    fit: MarkerFit, meas: tuple[Measurements, ...], settings: MarkerSettings
) -> QualityVerdict:
    """The gate's verdict on a marker fit (before the held-out judgement)."""
    if len(meas) == 1:
        return check_quality(fit.result, meas[0], mech=fit.registration.mechanism,
                             limits=settings.limits, instrument=settings.instrument)  # fmt: skip
    # the gate's per-pose tests assume one measured frame: judged without them
    verdict = check_quality(fit.result, stacked_measurements(meas), limits=settings.limits,
                            instrument=settings.instrument)  # fmt: skip
    issues = tuple(
        QualityIssue(i.kind, False, i.message + " (a warning: not confirmed by a refit)")
        if i.kind == "outliers" and i.refuse
        else i
        for i in verdict.issues
    )
    return dataclasses.replace(verdict, issues=issues)


def calibrate_markers(
    model: str,
    data: str | Path,
    setup: MarkerSetup,
    settings: MarkerSettings | None = None,
    progress: Progress | None = None,
) -> MarkerRun:
    """Read the marker table, settle prior and loss, fit, judge (see :class:`MarkerRun`).

    Args:
        model: model name or file (as :func:`pincal.measure.marker_mechanism` takes it).
        data: the marker table.
        setup: what is measured and known (link, columns, instrument frame, marker).
        settings: prior, loss, preset, gate (default :class:`MarkerSettings`).
        progress: called with a line before each long step.

    Raises:
        UnknownNameError: the preset is not one of the marker model's.
        PincalError subclasses of reading the table and of the fit.
    """
    settings = settings or MarkerSettings()
    say = progress or (lambda line: None)
    setup, copies = distinct_markers(data, setup)
    mech = marker_mechanism(model, setup)
    read = read_marker_data(data, mech, setup)
    meas = tuple(read.sets)
    notes = [*copies, *read.notes]
    if settings.preset not in mech.presets:
        raise UnknownNameError("preset", settings.preset, sorted(mech.presets),
                               " (the presets of a marker calibration, --params)")  # fmt: skip
    k, seed = settings.folds, settings.seed
    if len(meas[0]) < k:
        raise TooFewPosesError(
            f"{len(meas[0])} poses: a marker calibration is judged by {k}-fold held-out "
            f"prediction, so it needs at least {k} poses (and enough to fit the instrument "
            f"frame, the marker and the robot's parameters: tens in practice); measure more"
        )
    say(f"registering the instrument frame and {len(meas)} marker(s), then identifying from "
        f"{len(meas[0])} poses; {k}-fold cross-validation judges the fit")  # fmt: skip
    registrations = Registrations(mech, setup)  # each set of poses registered once
    baseline = cross_validate(registration_procedure(mech, setup, registrations), meas, k, seed)
    asked = parse_prior(settings.prior)
    machine = any(not is_registration(n) for n in parameters(mech, settings.preset).names)
    if not machine:
        asked = None  # only the registration is fitted: no prior, no baseline to beat

    def settle(loss: str) -> tuple[PriorChoice, MarkerFit, QualityVerdict]:
        procedure = marker_procedure(mech, setup, settings.preset, settings.method, loss,
                                     registrations)  # fmt: skip
        if asked == "auto":
            say(f"choosing the prior's strength by {k}-fold cross-validation ({loss} loss)")
            choice = choose_prior(procedure, meas, k, seed)
        else:
            choice = cross_validated(procedure, asked, meas, k, seed)  # type: ignore[arg-type]
        fit = fit_markers(mech, setup, meas, settings.preset, settings.method, choice.prior,
                          loss=loss, registration=registrations(meas))  # fmt: skip
        return choice, fit, _gate(fit, meas, settings)

    loss = "linear" if settings.loss == "auto" else settings.loss
    choice, fit, verdict = settle(loss)
    if settings.loss == "auto" and verdict.outlier_poses:
        named = ", ".join(map(str, verdict.outlier_poses[:12]))
        notes.append(f"loss auto: the least-squares fit has outlying poses ({named}); refitted "
                     f"with the {ROBUST_LOSS} loss (least squares within 1.345σ, linear "
                     "beyond)")  # fmt: skip
        loss = ROBUST_LOSS
        choice, fit, verdict = settle(loss)
    evidence = None
    if machine:
        cv = choice.cv
        if choice.chosen:  # the choice is part of the procedure: nested CV
            say("cross-validating the calibration, the prior chosen again in each fold")
            procedure = marker_procedure(mech, setup, settings.preset, settings.method, loss,
                                         registrations)  # fmt: skip
            nested = nested_choice(procedure, k, seed)
            cv = cross_validate(nested, meas, k, seed)
            if nested.leave_one_out:
                notes.append(_leave_one_out_note(nested.leave_one_out, k))
        # with orientation measured, both blocks count, each whitened by the noise σ
        # the procedure's fold fits leave (the same σ for both procedures)
        evidence = HeldOutEvidence(cv, baseline, "registration only", cv.fit_scales())
        verdict = held_out_verdict(verdict, evidence, fit.result)
    rms = fit.registration.fit.rms
    warnings: tuple[str, ...] = (_misfit_note(rms),) if rms > MISFIT_RMS else ()
    angle = fit.registration.orientation_rms
    if angle is not None and angle > MISFIT_ANGLE:
        warnings += (_angle_note(angle),)
    return MarkerRun(fit, meas, setup, settings, loss, choice, verdict,
                     (*notes, *fit.notes), warnings, evidence if machine else None)  # fmt: skip

