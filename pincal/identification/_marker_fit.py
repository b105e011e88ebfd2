"""Identification from marker positions: registration first, then a guarded joint fit.

:func:`fit_markers` is what ``pincal calibrate --link`` runs:

1. the instrument frame and the marker offset in closed form
   (:func:`pincal.measure.register_markers`);
2. one identification of the machine's parameters together with both (Gauss–Newton,
   with the optional Gaussian prior of :class:`Prior` on the machine's parameters);
   when Gauss–Newton does not converge, Levenberg–Marquardt takes over from the same
   start, and the switch is noted;
3. machine parameters whose 2σ exceeds a physical bound (``bounds``) held at their
   nominal values and the fit repeated;
4. the identifiable set decided again *at the solution* (the start can hide
   parameters, e.g. a marker guessed on the last joint axis), and the fit repeated
   from there when it differs — each said in words in :attr:`MarkerFit.notes`.

Steps 2–4 are the fit driver's (:func:`pincal.identification.solvers._driver.drive_holding`
over :func:`pincal.identification.solvers._driver.drive`); this module registers and states
the policies.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pincal.identification._held import with_held
from pincal.identification._identify import fitted_at_start, identify
from pincal.identification._options import GaussNewtonOptions, LMOptions
from pincal.identification.problem import IdentificationProblem, MarkerSetProblem
from pincal.identification.results import IdentificationResult
from pincal.identification.solvers import MarginalBound, drive_holding
from pincal.measure import (
    MarkerRegistration,
    MarkerSetup,
    Measurements,
    marker_mechanisms,
    register_markers,
)
from pincal.model import BASE_JOINT, TOOL_JOINT, Mechanism, ParameterSet
from pincal.sensitivity import PLACEMENT_BOUND, parameters

__all__ = ["REGISTRATION_PRESET", "MarkerFit", "Prior", "fit_markers", "is_registration"]

#: the preset of the registration-only model (instrument frame + marker)
REGISTRATION_PRESET = "base_tool"


_MARKER_JOINT = re.compile(r"marker\d+_frame\.")


def is_registration(name: str) -> bool:
    """True for an instrument-frame or marker parameter.

    Those are ``base_frame.*``, ``tool_frame.*`` and ``marker<k>_frame.*``.
    """
    return name.startswith((f"{BASE_JOINT}.", f"{TOOL_JOINT}.")) or bool(_MARKER_JOINT.match(name))


@dataclass(frozen=True)
class Prior:
    """A Gaussian prior on the machine's parameters about their nominal values.

    Attributes:
        length: 1σ of length parameters [m] (inf = none).
        angle: 1σ of angle parameters (rotations and revolute offsets) [rad].
    """

    length: float
    angle: float

    def scaled(self, s: float) -> Prior:
        """The prior with both σ multiplied by ``s``."""
        return Prior(self.length * s, self.angle * s)

    def describe(self) -> str:
        """The σ in words, e.g. ``σ 10 mm / 10 mrad``."""
        return f"σ {self.length * 1e3:.3g} mm / {self.angle * 1e3:.3g} mrad"


@dataclass(frozen=True)
class MarkerFit:
    """A fit of :func:`fit_markers`.

    Attributes:
        result: the identification (parameters of ``registration.mechanism``).
        registration: the closed-form start.
        notes: what the guards did, in words (switches, parameters held and why).
        method: the solver that produced ``result``.
        held_weak: machine parameters held at nominal because their 2σ exceeded the
            bounds (named in ``notes`` too).
    """

    result: IdentificationResult
    registration: MarkerRegistration
    notes: tuple[str, ...]
    method: str
    held_weak: tuple[str, ...] = ()

    @property
    def calibrated(self) -> Mechanism:
        """The calibrated mechanism (instrument frame and marker included)."""
        return self.result.calibrated_mechanism


def _prior_std(params: ParameterSet, setup: MarkerSetup, prior: Prior | None) -> np.ndarray:
    std = np.full(len(params), np.inf)
    for i, (name, unit) in enumerate(zip(params.names, params.units, strict=True)):
        if name.startswith(f"{TOOL_JOINT}.t") and setup.marker_std is not None:
            std[i] = setup.marker_std
        elif prior is not None and not is_registration(name):
            std[i] = prior.length if unit == "m" else prior.angle
    return std


def _fit(
    mech: Mechanism | tuple[Mechanism, ...],
    params: ParameterSet,
    meas: Measurements | tuple[Measurements, ...],
    names: list[str],
    method: str,
    std: np.ndarray,
    loss: str = "linear",
    initial: np.ndarray | None = None,
    max_iterations: int = 100,
) -> IdentificationResult:
    prior: dict = {}
    if np.isfinite(std).any():
        prior = {"prior_std": tuple(std), "prior_mean": tuple(np.zeros(len(std)))}
    opts: GaussNewtonOptions | LMOptions | None = None
    if method == "gauss-newton":
        # fit_markers switches to lm itself (and keeps the method it used): no fallback
        opts = GaussNewtonOptions(max_iterations=max_iterations, fallback=False, loss=loss,
                                  **prior)  # fmt: skip
    elif method == "lm":
        opts = LMOptions(max_iterations=max_iterations, loss=loss, **prior)
    return identify(_problem(mech, params, meas, names, initial), method=method, options=opts)


def _problem(
    mech: Mechanism | tuple[Mechanism, ...],
    params: ParameterSet,
    meas: Measurements | tuple[Measurements, ...],
    names: list[str],
    initial: np.ndarray | None,
) -> IdentificationProblem:
    if isinstance(mech, tuple):  # several markers: one problem over their stacked rows
        assert isinstance(meas, tuple)
        return MarkerSetProblem.build(mech, params, meas, initial, names)
    assert isinstance(meas, Measurements)
    return IdentificationProblem(mech, params, meas, initial, names)


def fit_markers(
    mech: Mechanism,
    setup: MarkerSetup,
    measurements: Measurements | Sequence[Measurements],
    preset: str = "chain",
    method: str = "gauss-newton",
    prior: Prior | None = None,
    bounds: tuple[float, float] = PLACEMENT_BOUND,
    registration_only: bool = False,
    loss: str = "linear",
    max_iterations: int = 100,
    registration: MarkerRegistration | None = None,
) -> MarkerFit:
    """Register, then identify the machine with the instrument frame and marker.

    Args:
        mech: from :func:`pincal.measure.marker_mechanism`.
        setup: what is known (instrument frame, marker, its σ).
        measurements: marker positions [m] in the instrument frame; with several
            markers (``setup.more_columns``), one set per marker (same rows, from
            :func:`pincal.io.read_marker_sets`), fitted together (one instrument frame,
            an offset each).
        preset: parameter preset of the full model (``chain``: every joint's geometry).
        method: ``gauss-newton`` (falls back to ``lm``) or another registered solver.
        prior: prior on the machine's parameters (Gauss–Newton only), or None.
        bounds: (length [m], angle [rad]) largest plausible 2σ of a machine parameter;
            a parameter above it is held at its nominal value.
        registration_only: fit only the instrument frame and the marker (the baseline
            of an uncalibrated robot).
        loss: robust loss (Gauss–Newton re-weighted, or ``lm``; see ``LMOptions.loss``).
        max_iterations: iteration limit of each solve (``lm``: 10 × evaluations).
        registration: the closed-form registration of these measurements (from
            :func:`pincal.measure.register_markers` with this set-up), when the caller
            already has it; None registers them here.

    Raises:
        PincalError subclasses of :func:`identify` and :func:`register_markers`.
    """
    parts = (measurements,) if isinstance(measurements, Measurements) else tuple(measurements)
    reg = registration or register_markers(
        mech,
        parts[0],
        marker_known=setup.marker is not None,
        frame_known=setup.instrument_frame == "known",
        more=parts[1:],
    )
    start: Mechanism | tuple[Mechanism, ...] = reg.mechanism
    meas: Measurements | tuple[Measurements, ...] = parts[0]
    if len(parts) > 1:
        start, meas = marker_mechanisms(reg.mechanism, setup), parts
    params = parameters(reg.mechanism, REGISTRATION_PRESET if registration_only else preset)
    names = [n for n in params.names if n not in setup.held]
    std = _prior_std(params, setup, None if registration_only else prior)
    if registration_only:
        result = _fit(start, params, meas, names, "gauss-newton", std)
        return MarkerFit(result, reg, (), "gauss-newton")
    if method not in ("gauss-newton", "lm"):
        result = _fit(start, params, meas, names, method, std)
        return MarkerFit(result, reg, (), method)

    def one(names: list[str], used: str, initial: np.ndarray | None) -> IdentificationResult:
        # the refinement from a solution runs with the default iteration limit
        limit = max_iterations if initial is None else 100
        return _fit(start, params, meas, names, used, std, loss, initial, limit)

    def counted(names: list[str], initial: np.ndarray) -> int | None:
        return fitted_at_start(_problem(start, params, meas, names, initial))

    bound = MarginalBound(*bounds)
    out = drive_holding(one, names, method, bound, is_registration, counted)
    result = with_held(out.result, out.held, f"placed beyond {bound.describe()} by the poses")
    return MarkerFit(result, reg, out.notes, out.method, out.held)
