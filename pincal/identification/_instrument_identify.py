"""Joint machine + instrument identification: choose what to fit, solve, finish.

:func:`joint_fit` solves an :class:`pincal.identification.InstrumentProblem` with a
registered local solver (``"gauss-newton"`` or ``"lm"``), fitting the identifiable base
set (instrument parameters first, so what an instrument absorbs is held on the machine
side) less the directions the data place only beyond a bound, names what it did not
calibrate (:mod:`pincal.identification.problem._gauge`) and ends in the finishing step every
identification shares (:mod:`pincal.identification.solvers._finish`). The sequence is the one
fit driver's (:func:`pincal.identification.solvers._driver.drive`) with the joint set rule and a
1σ :class:`pincal.identification.problem._fit_set.WeakBound`; the joint details are typed
(:class:`pincal.identification.JointDetails` on ``result.joint``).
:func:`pincal.identification.identify` runs it for an
:class:`pincal.identification.IdentificationProblem` of several data sets;
:func:`identify_instruments` is the convenience that also returns the joint details.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from pincal.errors import SolverOptionError
from pincal.identification.problem import (
    DataBlock,
    Dataset,
    InstrumentProblem,
    JointBase,
    WeakBound,
    constant_line,
    constant_std,
)
from pincal.identification.results import IdentificationResult, JointDetails, ResidualStats
from pincal.identification.solvers import FitPolicy, SolverOptions, drive, finish, solver
from pincal.model import Mechanism, ParameterSet
from pincal.sensitivity import PLACEMENT_BOUND, Identifiability

__all__ = ["SCALE_STD_LIMIT", "InstrumentIdentification", "identify_instruments", "joint_fit"]

#: a constant an instrument file declares and the fit trusts (a reading scale, a sphere
#: radius) is named in the gauge when the data tell it only beyond this 1σ relative to
#: its value [1] (see docs/quality_gate.md, "Instrument files")
SCALE_STD_LIMIT = 1e-3


@dataclass(frozen=True)
class InstrumentIdentification:
    """Outcome of :func:`identify_instruments`.

    Attributes:
        result: the machine part as an :class:`IdentificationResult` (marginal
            covariance of the machine base parameters; residual statistics over every
            dataset, scalar readings counted as position residuals [m]; ``result.joint``
            holds the instrument values, gauge and redundancy).
        names: all joint parameter names (machine, then ``label.θ`` names).
        values: (n + Σk,) joint values at the solution [SI]; x0: start values.
        fitted: indices (into ``names``) of the fitted base set.
        covariance: covariance of the fitted values (order of ``fitted``).
        residuals: per dataset, (m_i, k_i) raw residuals at the solution [m, rad].
        identifiability: joint analysis at the start (instrument parameters first).
        gauge: what the data do not observe (held at nominal), and the constants the files
            declare that the data tell only beyond 1e-3 of their value, in words.
        weak: names of the parameters held because the data place them only beyond
            20 mm / 0.1 rad (1σ).
        whitened: (m, k, p) Jacobian of the fitted parameters per pose and (m, k)
            residuals, both divided by their σ, at the solution — for the quality gate's
            per-pose tests; None when the poses have residuals of different sizes or a
            plate's known distances add rows.
        socket_centres: ``"plate.socket"`` → (3,) identified socket centre [m].
        warnings: what no measurement fixes, in words (e.g. the length scale of a
            socket campaign without a known distance).
    """

    result: IdentificationResult
    names: tuple[str, ...]
    values: np.ndarray
    x0: np.ndarray
    fitted: np.ndarray
    covariance: np.ndarray
    residuals: list[np.ndarray]
    identifiability: Identifiability
    gauge: tuple[str, ...] = ()
    weak: tuple[str, ...] = ()
    whitened: tuple[np.ndarray, np.ndarray] | None = None
    socket_centres: dict[str, np.ndarray] = field(default_factory=dict)
    warnings: tuple[str, ...] = ()

    def instrument_values(self) -> dict[str, float]:
        """Instrument parameter name → identified (or start) value [SI]."""
        n = len(self.result.names)
        return {k: float(v) for k, v in zip(self.names[n:], self.values[n:], strict=True)}


def _stats(raws: list[np.ndarray], blocks: Sequence[DataBlock]) -> ResidualStats:
    """Residual statistics over the poses of every block (a plate's distances left out)."""
    pos: list[float] = []
    rot: list[float] = []
    for raw, b in zip(raws, blocks, strict=False):
        p, r = b.norms(raw)
        pos += p
        rot += r
    out = []
    for e in (np.array(pos), np.array(rot)):
        out += [float(np.sqrt(np.mean(e**2))), float(e.max())] if e.size else [np.nan, np.nan]
    return ResidualStats(*out)


def identify_instruments(
    mech: Mechanism,
    params: ParameterSet,
    datasets: Sequence[Dataset],
    method: str = "gauss-newton",
    *,
    options: SolverOptions | None = None,
    labels: Sequence[str] | None = None,
    progress: Callable[[int, float], None] | None = None,
    weak_bound: tuple[float, float] | None = PLACEMENT_BOUND,
) -> InstrumentIdentification:
    """Identify machine and instrument parameters jointly from several datasets.

    The joint fit of ``identify(IdentificationProblem(mech, params, datasets,
    labels=labels, weak_bound=weak_bound), method, options=options)`` — the same
    :class:`IdentificationResult`, as ``.result`` — with what only a joint fit has
    (instrument values, gauge, socket centres, whitened per-pose Jacobian for the
    gate). It runs the joint fit for any data, a single pose file included.

    Args:
        mech: nominal mechanism.
        params: the n machine parameters.
        datasets: :class:`Measurements`, :class:`InstrumentData` and/or
            :class:`SocketData` (any mix).
        method: ``"gauss-newton"`` or ``"lm"``.
        options: that solver's options dataclass (``GaussNewtonOptions`` or
            ``LMOptions``; None = its defaults).
        labels: names of the datasets (prefix of the instrument parameter names).
        progress: optional ``(iteration, cost)`` callback passed to the solver.
        weak_bound: (length [m], angle [rad]): a direction of the base set whose 1σ
            (at the files' declared noise) exceeds it is held at nominal too, named in
            the gauge (see :func:`pincal.identification.problem._gauge.weak_parameters`); None
            fits the whole identifiable base set.

    Returns:
        InstrumentIdentification (the machine part is an IdentificationResult).

    Raises:
        SolverOptionError: a method other than the local solvers.
        MeasurementError: inconsistent datasets.
    """
    model = InstrumentProblem(mech, params, datasets, labels)
    return joint_fit(model, method, options, progress, weak_bound)


def joint_fit(
    model: InstrumentProblem,
    method: str,
    options: SolverOptions | None,
    progress: Callable[[int, float], None] | None,
    weak_bound: tuple[float, float] | None,
) -> InstrumentIdentification:
    """Solve a joint residual model and finish it (see :func:`identify_instruments`).

    Raises:
        SolverOptionError: a method other than the local solvers, or foreign options.
    """
    if method not in ("gauss-newton", "lm"):
        raise SolverOptionError(
            f"joint instrument identification runs 'gauss-newton' or 'lm', not {method!r}"
        )
    entry = solver(method)
    opts = entry.check_options(options)
    params = model.params
    x0 = model.x0
    weak_rule = None if weak_bound is None else WeakBound(*weak_bound)
    policy = FitPolicy(JointBase(), weak_rule, noise_floor=True)
    d = drive(model, x0, entry, opts, policy, progress)
    ident, settled, free, weak = d.fit_set.identifiability, d.settled, d.free, d.weak
    out, raw0, gauge = settled.out, d.raw0, d.fit_set.gauge
    if weak.size:
        assert weak_rule is not None
        gauge += (f"seen too weakly to place within {weak_rule.describe()}, held at nominal: "
                  f"{', '.join(model.names[i] for i in weak)}",)  # fmt: skip
    raws, Jf = settled.raw, settled.Jf
    constants = model.declared_constants(np.asarray(out.x, dtype=float))
    several = len({label for label, _, _ in constants}) > 1
    for label, c, column in constants:
        std = constant_std(Jf, column)
        if std > SCALE_STD_LIMIT * abs(c.value):
            gauge += (constant_line(c, std, label if several else None),)
    n, x = model.n_machine, np.asarray(out.x, dtype=float)
    centres = model.socket_centres(x)
    result, cov = finish(
        model, settled, method=method, params=params, raw0=raw0,
        stats=lambda raws: _stats(raws, model.blocks),
        residuals=np.concatenate(  # per pose (a plate's known distances are not poses)
            [np.linalg.norm(a, axis=1) for a in raws[: len(model.datasets)]]
        )[:, None],
        initial_values=np.zeros(n),
        prefix=f"joint fit of {free.size} of {len(model.names)} parameters (the others "
        "held at nominal: see the gauge); "
        + "".join(f"WARNING: {w}; " for w in model.scale_warnings),
        identifiability=ident,
        joint=JointDetails(
            {k: float(v) for k, v in zip(model.names[n:], x[n:], strict=True)},
            tuple(model.labels), settled.dof, gauge, model.scale_warnings,
            {k: tuple(float(v) * 1e3 for v in c) for k, c in centres.items()},
        ),
    )  # fmt: skip
    r = settled.r
    ks = {a.shape[1] for a in raws}
    whitened = None
    if len(raws) == len(model.datasets) and len(ks) == 1:
        k = ks.pop()
        whitened = (Jf.reshape(-1, k, free.size), r.reshape(-1, k))
    return InstrumentIdentification(
        result, model.names, x, x0, free, cov, raws, ident, gauge,
        tuple(model.names[i] for i in weak), whitened, centres, model.scale_warnings,
    )  # fmt: skip
