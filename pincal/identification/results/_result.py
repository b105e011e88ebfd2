"""One result shape for every identification solver: a record, and the live calibration.

:class:`IdentificationRecord` is what ``identification.json`` holds: the full parameter
vector with a mask of what was identified, the covariance of the identified ones,
residual statistics, the solver's iterations / success / message, its typed extras
(:class:`QPSOExtras`, :class:`StepPlanningExtras`, :class:`LocalSolverExtras`) and an
:class:`IdentifiabilitySummary`. :class:`IdentificationResult` (what :func:`pincal.identify`
returns) is a record that also holds the live calibration: the parameter set, the
calibrated mechanism and the identifiability analysis.
:func:`pincal.identification.result_to_dict` writes either as the document of
``identification.json``; ``result_from_dict`` reads it back as a record.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pincal.errors import ParameterError, PincalError
from pincal.identification._weighting import Weighting
from pincal.identification.results._joint_details import JointDetails
from pincal.model import Mechanism, ParameterSet
from pincal.sensitivity import GlobalSensitivity, Identifiability, parameters

__all__ = [
    "IdentifiabilitySummary",
    "IdentificationRecord",
    "IdentificationResult",
    "LocalSolverExtras",
    "QPSOExtras",
    "ResidualStats",
    "SolverExtras",
    "StepPlanningExtras",
]


@dataclass(frozen=True)
class ResidualStats:
    """Residual statistics over the measured poses.

    Attributes:
        rms_position, max_position: of the position-error norm per pose [m] (NaN if
            position is not measured).
        rms_orientation, max_orientation: of the rotation-error norm per pose [rad]
            (NaN if orientation is not measured).
    """

    rms_position: float
    max_position: float
    rms_orientation: float
    max_orientation: float

    @classmethod
    def from_residuals(cls, r: np.ndarray, components: tuple[str, ...]) -> ResidualStats:
        """From unweighted residuals (m, k) in the given components."""
        pos = [i for i, c in enumerate(components) if c in ("x", "y", "z")]
        rot = [i for i, c in enumerate(components) if c.startswith("r")]
        out = []
        for cols in (pos, rot):
            if cols:
                norms = np.linalg.norm(r[:, cols], axis=1)
                out += [float(np.sqrt(np.mean(norms**2))), float(norms.max())]
            else:
                out += [float("nan"), float("nan")]
        return cls(*out)


@dataclass(frozen=True)
class LocalSolverExtras:
    """Extras of ``gauss-newton`` and ``lm``.

    Attributes:
        evaluations: residual evaluations (with or without Jacobian).
        rejected_steps: trial steps rejected (no decrease, or model not assembled).
        damping: final Levenberg damping μ relative to max diag(JᵀJ) (0 = pure
            Gauss–Newton; NaN for ``lm``, whose damping is internal to scipy).
    """

    evaluations: int
    rejected_steps: int = 0
    damping: float = float("nan")


@dataclass(frozen=True)
class QPSOExtras:
    """Extras of ``qpso`` and ``qpso-stepwise``.

    Attributes:
        cost: exact cost 0.5·‖r_w‖² at the result.
        initial_cost: exact cost at the start values.
        nfev: cost evaluations (particles) over all passes and stages.
        order: step-wise only: parameter indices (into the full vector) in the order the
            coarse stage fixed them; empty for the direct variant.
        seconds: wall time of the search [s].
        swarm_history: best cost of the cost model per swarm iteration (last pass, or the
            fine stage of the step-wise variant).
    """

    cost: float
    initial_cost: float
    nfev: int
    order: tuple[int, ...]
    seconds: float
    swarm_history: tuple[float, ...]


@dataclass(frozen=True)
class StepPlanningExtras:
    """Extras of ``step-planned``.

    Attributes:
        steps: (accepted steps, n) planned steps [SI] (full parameter vector).
        weights: (n,) normalised global sensitivities that planned the steps.
        sensitivity: the global sensitivity object (None when read from a file).
    """

    steps: np.ndarray
    weights: np.ndarray
    sensitivity: GlobalSensitivity | None = None


SolverExtras = LocalSolverExtras | QPSOExtras | StepPlanningExtras


@dataclass(frozen=True)
class IdentifiabilitySummary:
    """What ``identification.json`` keeps of the identifiability analysis at the start.

    Attributes:
        parameters: number of parameters analysed.
        rank: numerical rank (identifiable combinations).
        unidentifiable: names of the parameters that are not identifiable.
        explanation: the sentences of
            :meth:`pincal.sensitivity.Identifiability.describe` (the parameters that
            break loop closure in one line).
        breaks_closure: names of every parameter that breaks loop closure.
    """

    parameters: int
    rank: int
    unidentifiable: tuple[str, ...] = ()
    explanation: tuple[str, ...] = ()
    breaks_closure: tuple[str, ...] = ()

    @classmethod
    def of(cls, ident: Identifiability) -> IdentifiabilitySummary:
        """The summary of an analysis."""
        return cls(
            len(ident.names), int(ident.rank), ident.unidentifiable_names,
            tuple(ident.describe()), ident.breaks_closure_names,
        )


@dataclass(frozen=True)
class IdentificationRecord:
    """An identification as ``identification.json`` holds it (no live objects).

    :func:`pincal.identification.result_from_dict` (and :func:`pincal.io.read_identification`)
    return one; :class:`IdentificationResult` is a record with the live calibration.

    Attributes:
        method: solver name (``"gauss-newton"``, ``"lm"``, ``"qpso"``, ...).
        names: all n parameter names; units: ``"m"``/``"rad"`` per parameter (or a
            joint term's unit).
        full_values: (n,) values of all parameters [SI]; the ones not identified keep
            their start values.
        identified: (n,) bool mask of the identified parameters (k of them).
        std: (k,) standard deviations of the identified parameters [SI].
        covariance: (k, k) their covariance ``(Jᵀ W J)⁻¹`` with W from the declared or
            estimated noise (see ``weighting``).
        before, after: residual statistics at the start and identified values.
        reduced_chi2: weighted residual sum of squares / (N − k); with a prior, / (N − tr H),
            the regularised fit's redundancy.
        iterations: solver iterations (function evaluations for ``lm``).
        success: whether the solver reached its tolerance or the noise/solver floor.
        message: solver message, including any parameter reduction.
        cost_history: 0.5·‖weighted residual‖² per iteration.
        residuals: (m, c) unweighted residuals at the solution [m, rad].
        initial_values: (n,) start values [SI].
        n_equations: scalar measurement equations N.
        model: mechanism name; preset: parameter-set label.
        extras: solver-specific extras (see :data:`SolverExtras`), or None.
        annotations: JSON-ready context written with the result (data file, validation
            errors, simulated truth, index history, ...).
        weighting: the noise σ used (declared or estimated), the robust loss and the
            poses it down-weighted (:class:`Weighting`); None when not recorded.
        initial_residuals: (m, c) unweighted residuals at the start values [m, rad]
            (None when not recorded).
        components: names of the c residual columns (measured components, e.g.
            ``("x", "y", "rz")``); empty when unknown (scalar instrument readings, or
            files written before pincal recorded them).
        identifiability_summary: the identifiability analysis at the start values as
            recorded (None when not recorded).
        joint: a joint fit's instrument values, gauge, redundancy, warnings and socket
            centres (:class:`JointDetails`); None for other fits.
    """

    method: str
    names: tuple[str, ...]
    units: tuple[str, ...]
    full_values: np.ndarray
    identified: np.ndarray
    std: np.ndarray
    covariance: np.ndarray
    before: ResidualStats
    after: ResidualStats
    reduced_chi2: float
    iterations: int
    success: bool
    message: str
    cost_history: tuple[float, ...]
    residuals: np.ndarray
    initial_values: np.ndarray
    n_equations: int = 0
    model: str = ""
    preset: str = ""
    extras: SolverExtras | None = None
    annotations: Mapping[str, Any] = field(default_factory=dict, repr=False)
    weighting: Weighting | None = field(default=None, repr=False)
    initial_residuals: np.ndarray | None = field(default=None, repr=False)
    components: tuple[str, ...] = ()
    identifiability_summary: IdentifiabilitySummary | None = field(default=None, repr=False)
    joint: JointDetails | None = field(default=None, repr=False)

    @property
    def values(self) -> np.ndarray:
        """(k,) identified values [SI], in name order."""
        return self.full_values[self.identified]

    @property
    def identified_names(self) -> tuple[str, ...]:
        """Names of the parameters that were fitted (the others held at their initial values)."""
        return tuple(n for n, ok in zip(self.names, self.identified, strict=True) if ok)

    @property
    def fixed(self) -> tuple[str, ...]:
        """Names of the parameters held at their start values (not identified)."""
        return tuple(n for n, ok in zip(self.names, self.identified, strict=True) if not ok)

    def table(self) -> list[tuple[str, float, float, str]]:
        """(name, value, std, unit) per identified parameter [SI]."""
        units = [u for u, ok in zip(self.units, self.identified, strict=True) if ok]
        return list(zip(self.identified_names, self.values, self.std, units, strict=True))

    def applied_to(self, nominal: Mechanism) -> Mechanism:
        """``nominal`` with the recorded values of its preset's parameters applied.

        The parameter set is ``preset`` of ``nominal`` (``"full"`` when none is recorded);
        each of its parameters takes the recorded value (further recorded names, such as
        an instrument's unknowns, are not the machine's and are left out).

        Raises:
            ParameterError: the preset is not a preset of ``nominal``, or the record lacks
                one of its parameters (it was identified for another model).
        """
        preset = self.preset or "full"
        try:
            params = parameters(nominal, preset)
        except PincalError as exc:
            raise ParameterError(
                f"the identification of {self.model!r} (preset {preset!r}) does not apply "
                f"to model {nominal.name!r} ({exc}); give the model it was identified for"
            ) from None
        index = {n: k for k, n in enumerate(self.names)}
        missing = [n for n in params.names if n not in index]
        if missing:
            raise ParameterError(
                f"the identification of {self.model!r} (preset {preset!r}) lacks "
                f"{len(missing)} parameters of model {nominal.name!r} (e.g. {missing[0]!r}); "
                "give the model it was identified for"
            )
        values = np.array([self.full_values[index[n]] for n in params.names], dtype=float)
        return params.apply(nominal, values)


@dataclass(frozen=True)
class IdentificationResult(IdentificationRecord):
    """Outcome of :func:`pincal.identify` for every solver: the record and the live parts.

    Attributes (beyond :class:`IdentificationRecord`'s):
        parameter_set: the full parameter set (n parameters, in ``names`` order).
        calibrated_mechanism: the mechanism with ``full_values`` applied (also
            :attr:`calibrated`).
        identifiability: analysis at the start values; ``identifiability_summary`` is
            derived from it.
        prior: the Gaussian prior of the fit, (1/σ (n_x,), mean (n_x,)) over every
            unknown [1/SI, SI], weight 0 where there is none; None without a prior. A
            refit of the same cost (the gate's refit without outliers) uses it.
    """

    parameter_set: ParameterSet = field(kw_only=True, repr=False)
    calibrated_mechanism: Mechanism = field(kw_only=True, repr=False)
    identifiability: Identifiability = field(kw_only=True, repr=False)
    prior: tuple[np.ndarray, np.ndarray] | None = field(default=None, kw_only=True, repr=False)
    identifiability_summary: IdentifiabilitySummary | None = field(
        default=None, init=False, repr=False
    )

    def __post_init__(self) -> None:
        object.__setattr__(
            self, "identifiability_summary", IdentifiabilitySummary.of(self.identifiability)
        )

    @property
    def params(self) -> ParameterSet:
        """The identified parameters as a set (the base set when reduced)."""
        return self.parameter_set.subset(np.flatnonzero(self.identified))

    @property
    def calibrated(self) -> Mechanism:
        """The mechanism with ``full_values`` applied."""
        return self.calibrated_mechanism
