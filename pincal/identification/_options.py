"""Frozen, validated options of the local solvers and of step planning.

Each registered solver has its own options dataclass; a bad value raises
:class:`pincal.errors.SolverOptionError` (a :class:`pincal.ParameterError`) naming the
option and its valid range when the options are built, before any solving starts.
The QPSO options live with the QPSO solver (:class:`QPSOOptions`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pincal.errors import SolverOptionError
from pincal.identification._weighting import ROBUST_F_SCALE
from pincal.sensitivity import GlobalSensitivity

__all__ = [
    "LOSSES",
    "GaussNewtonOptions",
    "LMOptions",
    "StepPlanningOptions",
    "check_int",
    "check_real",
    "f_scale",
]

#: robust losses (``gauss-newton``: re-weighted steps; ``lm``: scipy.optimize.least_squares)
LOSSES = ("linear", "huber", "soft_l1", "cauchy", "arctan")


def check_int(owner: str, name: str, value: object, low: int, high: int | None = None) -> None:
    """Raise SolverOptionError unless ``value`` is an integer in [low, high]."""
    ok = (
        isinstance(value, (int, np.integer))
        and not isinstance(value, bool)
        and value >= low
        and (high is None or value <= high)
    )
    if not ok:
        valid = f"an integer ≥ {low}" if high is None else f"an integer in [{low}, {high}]"
        raise SolverOptionError(f"{owner}.{name} must be {valid}, got {value!r}")


def check_real(
    owner: str,
    name: str,
    value: object,
    low: float,
    high: float = math.inf,
    *,
    open_low: bool = False,
) -> None:
    """Raise SolverOptionError unless ``value`` is a finite real in [low, high].

    With ``open_low`` the interval is (low, high].
    """
    ok = (
        isinstance(value, (int, float, np.floating))
        and not isinstance(value, bool)
        and math.isfinite(float(value))
        and value <= high
        and (value > low if open_low else value >= low)
    )
    if not ok:
        bracket = "(" if open_low else "["
        top = "∞)" if math.isinf(high) else f"{high:g}]"
        raise SolverOptionError(
            f"{owner}.{name} must be a finite number in {bracket}{low:g}, {top}, got {value!r}"
        )


def _check_prior(opts: GaussNewtonOptions | LMOptions, owner: str) -> None:
    """Validate and normalise ``opts.prior_std`` / ``opts.prior_mean`` (tuples of floats)."""
    if (opts.prior_std is None) != (opts.prior_mean is None):
        raise SolverOptionError(f"{owner}: give prior_std and prior_mean together")
    if opts.prior_std is not None and opts.prior_mean is not None:
        std = tuple(float(v) for v in opts.prior_std)
        mean = tuple(float(v) for v in opts.prior_mean)
        if len(std) != len(mean) or any(not v > 0 for v in std):
            raise SolverOptionError(
                f"{owner}.prior_std must hold one σ > 0 (inf = none) per prior_mean entry"
            )
        object.__setattr__(opts, "prior_std", std)
        object.__setattr__(opts, "prior_mean", mean)


def _check_loss(opts: GaussNewtonOptions | LMOptions, owner: str) -> None:
    if opts.loss not in LOSSES:
        raise SolverOptionError(f"{owner}.loss must be one of {LOSSES}, got {opts.loss!r}")
    if opts.f_scale is not None:
        check_real(owner, "f_scale", opts.f_scale, 0.0, open_low=True)


def f_scale(opts: GaussNewtonOptions | LMOptions) -> float:
    """The robust loss' soft margin [σ]: the option, or the loss' 3σ-at-weight-½ default."""
    return float(ROBUST_F_SCALE[opts.loss] if opts.f_scale is None else opts.f_scale)


def _prior_weights(
    opts: GaussNewtonOptions | LMOptions, n: int
) -> tuple[np.ndarray, np.ndarray] | None:
    if opts.prior_std is None or opts.prior_mean is None:
        return None
    if len(opts.prior_std) != n:
        raise SolverOptionError(
            f"{type(opts).__name__}.prior_std has {len(opts.prior_std)} entries for {n} "
            "parameters"
        )
    return 1.0 / np.asarray(opts.prior_std), np.asarray(opts.prior_mean)


@dataclass(frozen=True)
class GaussNewtonOptions:
    """Options of ``"gauss-newton"``.

    Each iteration tries the full Gauss–Newton step; a trial whose model cannot be
    assembled or solved counts as no decrease. When it does not decrease the cost, the
    step is damped Levenberg–Marquardt style (``(JᵀJ + μ·diag(JᵀJ)) δ = −Jᵀr``, μ from
    ``damping_start`` up ×10 per rejected trial, down ÷10 per accepted step until pure
    Gauss–Newton again). With ``damping=False`` the step is halved instead (pincal 0.1).

    Attributes:
        max_iterations: iteration limit (≥ 1).
        xtol: relative step tolerance (> 0).
        regularization: Tikhonov weight λ ≥ 0 on ``‖x − initial‖²`` (whitened units).
        max_halvings: trial lengths 1, ½, ¼, … of the line search used when
            ``damping`` is False (1–60).
        damping: damp rejected steps (True) or halve them (False).
        damping_start: first μ of the damping (> 0, ≤ 1).
        prior_std: a Gaussian prior: per parameter (all n, in the parameter set's
            order) its 1σ [m or rad] about ``prior_mean``; ``inf`` = no prior on that
            parameter. The cost becomes ``½‖r‖² + ½ Σ ((x_i − mean_i)/σ_i)²`` with ``r``
            the whitened residual (a maximum a posteriori fit); None = no prior.
        prior_mean: (n,) the prior's centre [m, rad] (required with ``prior_std``).
        fallback: continue with ``lm`` from where Gauss–Newton stopped unconverged.
        acceleration: when a full step fails, try it bent to second order along the
            residual's curvature before damping (geodesic acceleration; see
            :mod:`pincal.identification.solvers._acceleration`); False: straight steps only
            (a robust loss takes straight steps).
        loss: robust loss, one of :data:`LOSSES`, minimised by iteratively re-weighted
            Gauss–Newton steps; the same cost as ``lm``'s (the prior's rows included).
        f_scale: the robust loss' soft margin in σ, as :attr:`LMOptions.f_scale`.
    """

    max_iterations: int = 50
    xtol: float = 1e-10
    regularization: float = 0.0
    max_halvings: int = 20
    damping: bool = True
    damping_start: float = 1.0
    prior_std: tuple[float, ...] | None = None
    prior_mean: tuple[float, ...] | None = None
    fallback: bool = True
    acceleration: bool = True
    loss: str = "linear"
    f_scale: float | None = None

    def __post_init__(self) -> None:
        o = type(self).__name__
        check_int(o, "max_iterations", self.max_iterations, 1)
        check_real(o, "xtol", self.xtol, 0.0, open_low=True)
        check_real(o, "regularization", self.regularization, 0.0)
        _check_loss(self, o)
        for flag in ("fallback", "acceleration"):
            if not isinstance(getattr(self, flag), bool):
                raise SolverOptionError(
                    f"{o}.{flag} must be True or False, got {getattr(self, flag)!r}"
                )
        check_int(o, "max_halvings", self.max_halvings, 1, 60)
        check_real(o, "damping_start", self.damping_start, 0.0, 1.0, open_low=True)
        if not isinstance(self.damping, bool):
            raise SolverOptionError(f"{o}.damping must be True or False, got {self.damping!r}")
        _check_prior(self, o)

    def prior_weights(self, n: int) -> tuple[np.ndarray, np.ndarray] | None:
        """(1/σ (n,), mean (n,)) of the prior, 0 weight where σ is inf; None without one."""
        return _prior_weights(self, n)


@dataclass(frozen=True)
class LMOptions:
    """Options of ``"lm"`` (``scipy.optimize.least_squares``).

    Attributes:
        max_iterations: the evaluation limit is 10 × this (≥ 1).
        xtol: relative step tolerance (> 0).
        loss: robust loss, one of :data:`LOSSES` (``"linear"`` = plain least squares
            with scipy's ``lm``; the others use ``trf``).
        f_scale: the robust loss' soft margin in σ of the (whitened) residuals, i.e.
            tied to the noise (> 0); None: the loss' default, at which a residual of
            3σ gets the weight 0.5 (huber 1.5, soft_l1 √3, cauchy 3, arctan 3).
        prior_std, prior_mean: a Gaussian prior as in :class:`GaussNewtonOptions` (its
            rows join the whitened residuals and stay Gaussian under a robust loss).
    """

    max_iterations: int = 50
    xtol: float = 1e-10
    loss: str = "linear"
    f_scale: float | None = None
    prior_std: tuple[float, ...] | None = None
    prior_mean: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        o = type(self).__name__
        check_int(o, "max_iterations", self.max_iterations, 1)
        check_real(o, "xtol", self.xtol, 0.0, open_low=True)
        _check_loss(self, o)
        _check_prior(self, o)

    def prior_weights(self, n: int) -> tuple[np.ndarray, np.ndarray] | None:
        """(1/σ (n,), mean (n,)) of the prior, 0 weight where σ is inf; None without one."""
        return _prior_weights(self, n)


@dataclass(frozen=True)
class StepPlanningOptions:
    """Options of ``"step-planned"`` (seed 002's sensitivity-planned steps).

    Attributes:
        sensitivity: global sensitivity of the problem's parameters (None: computed over
            ``workspace``).
        workspace: actuator rows (m, n_act) or a sample count for the default sensitivity.
        damping: initial λ relative to max diag(JᵀJ) (≥ 0).
        max_iterations: accepted-step limit (≥ 1).
        xtol: stop when ``max_i |w_i Δ_i| ≤ xtol·(1 + max_i |w_i x_i|)`` (> 0).
    """

    sensitivity: GlobalSensitivity | None = None
    workspace: np.ndarray | int = 200
    damping: float = 1.0
    max_iterations: int = 100
    xtol: float = 1e-12

    def __post_init__(self) -> None:
        o = type(self).__name__
        check_real(o, "damping", self.damping, 0.0)
        check_int(o, "max_iterations", self.max_iterations, 1)
        check_real(o, "xtol", self.xtol, 0.0, open_low=True)
        if isinstance(self.workspace, (int, np.integer)) and not isinstance(self.workspace, bool):
            check_int(o, "workspace", self.workspace, 1)
