"""Joint machine + instrument identification from files of several measurement kinds.

:class:`InstrumentProblem` is a residual model beside
:class:`pincal.identification.CalibrationProblem`: the unknowns are
``x = [machine parameters (n); θ of instrument 1; θ of instrument 2; …]``. Each dataset
is either :class:`pincal.measure.Measurements` (pose, position, component subset, tracker
poses — residuals exactly as in ``CalibrationProblem``) or
:class:`pincal.measure.InstrumentData` (one scalar per pose) or
:class:`pincal.measure.SocketData` (a ball seated in sockets: three residuals per pose,
socket centres shared by the files of one plate and appended after every file's own
unknowns, one residual per known distance); every block is whitened by its own noise,
so several files of different kinds combine in one fit. The
Jacobian is analytic: ``∂v/∂p · ∂p/∂x`` with ``∂p/∂x`` from
:func:`pincal.sensitivity.pose_sensitivity`, and ``∂v/∂θ`` from the instrument.

:func:`identify_instruments` solves it with a registered local solver
(``"gauss-newton"`` or ``"lm"``), fitting the identifiable base set (instrument
parameters first, so what an instrument absorbs is held on the machine side).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pincal.errors import ConvergenceError, MeasurementError, SolverOptionError
from pincal.identification._covariance import covariance_from_jacobian
from pincal.identification._gauge import null_motions, reading_scale_std, weak_parameters
from pincal.identification._problem import TRIAL_FAILURES, CalibrationProblem
from pincal.identification._result import IdentificationResult, ResidualStats
from pincal.identification._socket_terms import SocketTerms
from pincal.identification._solvers import solver
from pincal.measure import (
    InstrumentData,
    Measurements,
    SocketData,
    initial_instrument_values,
)
from pincal.model import Mechanism, ParameterSet
from pincal.model.kernels import measurement_residual
from pincal.sensitivity import Identifiability, analyse_jacobian, pose_sensitivity
from pincal.sensitivity.kernels import jacobian_plan

__all__ = ["InstrumentIdentification", "InstrumentProblem", "identify_instruments"]

Dataset = InstrumentData | Measurements | SocketData
#: a reading scale the data tell only beyond this 1σ [1] is named in the gauge
SCALE_STD_LIMIT = 1e-3


class InstrumentProblem:
    """Whitened residuals and Jacobian of machine + instrument parameters.

    Args:
        mech: nominal mechanism; params: its n parameters.
        datasets: one or more :class:`Measurements` / :class:`InstrumentData`.
        labels: a label per dataset (default ``"<kind><i>"``), prefixing θ names.

    Raises:
        MeasurementError: no datasets, or a dataset of other joints / another frame.
    """

    def __init__(
        self,
        mech: Mechanism,
        params: ParameterSet,
        datasets: Sequence[Dataset],
        labels: Sequence[str] | None = None,
    ):
        datasets = list(datasets)
        if not datasets:
            raise MeasurementError("give at least one measurement dataset")
        self.mech, self.params, self.datasets = mech, params, datasets
        self.labels = (
            list(labels)
            if labels is not None
            else [
                f"{'pose' if isinstance(d, Measurements) else d.kind}{i}"
                for i, d in enumerate(datasets)
            ]
        )
        for d, label in zip(datasets, self.labels, strict=True):
            if tuple(d.actuated) != tuple(mech.actuated) or d.frame != mech.measured_frame:
                raise MeasurementError(
                    f"dataset {label!r} is of joints {list(d.actuated)} / frame {d.frame!r}; "
                    f"the model has {list(mech.actuated)} / {mech.measured_frame!r}"
                )
        qs = mech.configurations(np.vstack([d.q_act for d in datasets]))
        self.instruments: list[Any] = []
        theta0: list[np.ndarray] = []
        self.sigma: list[np.ndarray] = []
        names: list[str] = list(params.names)
        units: list[str] = list(params.units)
        start = 0
        self._ball_cols: dict[int, int] = {}  # dataset index → column of its ball_x
        for d, label in zip(datasets, self.labels, strict=True):
            m = len(d)
            if isinstance(d, Measurements):
                self.instruments.append(None)
                self.sigma.append(CalibrationProblem(mech, params, d).sigma)
            elif isinstance(d, SocketData):
                self.instruments.append(d)
                th = np.zeros(len(d.parameter_names))  # the ball: see _start_centres
                self._ball_cols[len(self.instruments) - 1] = len(names)
                theta0.append(th)
                self.sigma.append(np.full((m, 3), d.plate.std))
                names += [f"{label}.{n}" for n in d.parameter_names]
                units += ["m"] * th.size
            else:
                P = np.array([mech.frame_placement(q).translation for q in qs[start : start + m]])
                inst, th = initial_instrument_values(d, P)
                self.instruments.append(inst)
                theta0.append(th)
                self.sigma.append(np.full((m, 1), inst.std))
                names += [f"{label}.{n}" for n in inst.parameter_names]
                units += list(inst.parameter_units)
            start += m
        self.n_machine = len(params)
        self.sockets = SocketTerms(datasets, len(names), self._ball_cols)
        names += self.sockets.names
        units += ["m"] * len(self.sockets.names)
        if self.sockets.sigma is not None:
            self.sigma.append(self.sockets.sigma)
        self.names, self.units = tuple(names), tuple(units)
        self.x0 = np.concatenate(
            [np.zeros(self.n_machine), *theta0, np.zeros(len(self.sockets.names))]
        )
        self.sockets.start(mech, qs, self.x0)
        self._qs: np.ndarray | None = None
        self._cache: tuple[bytes, Mechanism] | None = None

    @property
    def fixes_scale(self) -> bool:
        """False when only sockets without a known distance were measured."""
        return self.sockets.fixes_scale

    @property
    def scale_warnings(self) -> tuple[str, ...]:
        """What no measurement fixes, in words (see :class:`SocketTerms`)."""
        return self.sockets.warnings

    def socket_centres(self, x: np.ndarray) -> dict[str, np.ndarray]:
        """``"plate.socket"`` → (3,) socket centre at ``x`` [m]."""
        return self.sockets.centres(x)

    @property
    def n_equations(self) -> int:
        return int(sum(s.size for s in self.sigma))

    @property
    def solver_floor_cost(self) -> float:
        """Cost of residuals at 100× the FK tolerance: below it, data are fitted exactly."""
        return 0.5 * float(sum(np.sum((100 * self.mech.options.tol / s) ** 2) for s in self.sigma))

    def mechanism(self, x: np.ndarray) -> Mechanism:
        """The mechanism with the machine part of ``x`` applied (cached for the last one)."""
        values = np.asarray(x, dtype=float)[: self.n_machine]
        key = values.tobytes()
        if self._cache is None or self._cache[0] != key:
            mech = self.mech if not np.any(values) else self.params.apply(self.mech, values)
            self._cache = (key, mech)
        return self._cache[1]

    def cost(self, x: np.ndarray) -> float:
        """0.5·‖whitened residual‖²; +inf when the model cannot be assembled."""
        try:
            r, _, _ = self.evaluate(x, jacobian=False)
        except TRIAL_FAILURES:
            return float("inf")
        return 0.5 * float(r @ r)

    def _configurations(self, mech: Mechanism) -> np.ndarray:
        rows = np.vstack([d.q_act for d in self.datasets])
        qs = np.empty((len(rows), mech.model.nq))
        for i, q_act in enumerate(rows):
            guess = None if self._qs is None else self._qs[i]
            try:
                qs[i] = mech.configuration(q_act, guess, pose_index=i)
            except ConvergenceError:
                if guess is None:
                    raise
                qs[i] = mech.configuration(q_act, None, pose_index=i)
        self._qs = qs
        return qs

    def evaluate(self, x: np.ndarray, jacobian: bool = True):
        """Whitened residual (N,), its Jacobian (N, n + Σk) or None, raw residuals per dataset.

        Residuals are ``measured − model`` [m, rad]; the third item is a list of
        (m_i, k_i) arrays, one per dataset.
        """
        x = np.asarray(x, dtype=float)
        n, values = self.n_machine, x[: self.n_machine]
        mech = self.mechanism(x)
        qs = self._configurations(mech)
        plan = jacobian_plan(mech, self.params) if jacobian else None
        r_all, J_all, raws = [], [], []
        start, col = 0, n
        blocks = zip(self.datasets, self.instruments, self.sigma[: len(self.datasets)], strict=True)
        for d, inst, sig in blocks:
            m = len(d)
            q_block = qs[start : start + m]
            start += m
            if jacobian:
                sens = [pose_sensitivity(mech, self.params, q, values, plan) for q in q_block]
                P = np.array([s.position for s in sens])
                Rs = [s.rotation for s in sens]
            else:
                placements = [mech.frame_placement(q) for q in q_block]
                P = np.array([T.translation for T in placements])
                Rs = [T.rotation for T in placements]
            if isinstance(d, SocketData):
                raw, J = self.sockets.block(d, x, col, n, P, Rs, sens if jacobian else None)
                col += len(d.parameter_names)
            elif isinstance(d, Measurements):
                rows = d.component_indices
                raw = np.empty((m, rows.size))
                J = np.zeros((m, rows.size, len(x)))
                for i in range(m):
                    R_meas = None if d.rotations is None else d.rotations[i]
                    r, D = measurement_residual(P[i], Rs[i], d.positions[i], R_meas)
                    raw[i] = r[rows]
                    if jacobian:
                        J[i, :, :n] = -(D @ sens[i].jacobian)[rows]
            else:
                k = len(inst.parameter_names)
                v, dv_dp, dv_dth = inst.predict(P, x[col : col + k], d.ids)
                raw = (d.values - v)[:, None]
                J = np.zeros((m, 1, len(x)))
                if jacobian:
                    Jp = np.array([s.jacobian[:3] for s in sens])  # (m, 3, n)
                    J[:, 0, :n] = -np.einsum("mi,min->mn", dv_dp, Jp)
                    J[:, 0, col : col + k] = -dv_dth
                col += k
            raws.append(raw)
            r_all.append((raw / sig).ravel())
            J_all.append((J / sig[:, :, None]).reshape(-1, len(x)))
        if len(self.sigma) > len(self.datasets):  # the known distances of the plates
            raw, J = self.sockets.distance_block(x)
            sig = self.sigma[-1]
            raws.append(raw)
            r_all.append((raw / sig).ravel())
            J_all.append((J / sig[:, :, None]).reshape(-1, len(x)))
        r_w = np.concatenate(r_all)
        return r_w, (np.vstack(J_all) if jacobian else None), raws

    def whitened_readings(self, raws: list[np.ndarray]) -> np.ndarray:
        """(N,) the model's scalar readings / σ at the residuals ``raws`` of :meth:`evaluate`.

        0 on the rows of poses and sockets: the Jacobian column of a relative scale
        error of the readings.
        """
        out = []
        for d, raw, sig in zip(self.datasets, raws, self.sigma, strict=False):
            if isinstance(d, InstrumentData):
                out.append((d.values - raw[:, 0]) / sig[:, 0])
            else:
                out.append(np.zeros(raw.size))
        out += [np.zeros(s.size) for s in self.sigma[len(self.datasets) :]]
        return np.concatenate(out)

    @property
    def order(self) -> np.ndarray:
        """The column order of :meth:`analyse`: instrument parameters first."""
        return np.r_[np.arange(self.n_machine, len(self.names)), np.arange(self.n_machine)]

    def analyse(self, x: np.ndarray | None = None, J: np.ndarray | None = None) -> Identifiability:
        """Identifiability of the joint parameters at ``x`` (default the start values).

        The instrument parameters are listed first so they enter the base first.
        ``J``: the whitened Jacobian at ``x`` when already evaluated.
        """
        if J is None:
            _, J, _ = self.evaluate(self.x0 if x is None else x)
        return analyse_jacobian(J[:, self.order], tuple(self.names[i] for i in self.order))

    def tool_points(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Tool points (m, 3) [m] of every pose at ``x`` and their sensitivities (m, 3, n)."""
        x = np.asarray(x, dtype=float)
        mech, values = self.mechanism(x), x[: self.n_machine]
        plan = jacobian_plan(mech, self.params)
        sens = [pose_sensitivity(mech, self.params, q, values, plan)
                for q in self._configurations(mech)]  # fmt: skip
        return np.array([s.position for s in sens]), np.array([s.jacobian[:3] for s in sens])


@dataclass(frozen=True)
class InstrumentIdentification:
    """Outcome of :func:`identify_instruments`.

    Attributes:
        result: the machine part as an :class:`IdentificationResult` (marginal
            covariance of the machine base parameters; residual statistics over every
            dataset, scalar readings counted as position residuals [m]; annotations
            hold the instrument values).
        names: all joint parameter names (machine, then ``label.θ`` names).
        values: (n + Σk,) joint values at the solution [SI]; x0: start values.
        fitted: indices (into ``names``) of the fitted base set.
        covariance: covariance of the fitted values (order of ``fitted``).
        residuals: per dataset, (m_i, k_i) raw residuals at the solution [m, rad].
        identifiability: joint analysis at the start (instrument parameters first).
        gauge: what the data do not observe (held at nominal), in words.
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


def _stats(raws: list[np.ndarray], datasets: Sequence[Dataset]) -> ResidualStats:
    pos, rot = [], []
    kinds: list[Dataset | None] = [*datasets, *[None] * (len(raws) - len(datasets))]
    for raw, d in zip(raws, kinds, strict=True):
        if isinstance(d, SocketData):
            pos += list(np.linalg.norm(raw, axis=1))
        elif isinstance(d, Measurements):
            comps = d.components
            ip = [i for i, c in enumerate(comps) if not c.startswith("r")]
            ir = [i for i, c in enumerate(comps) if c.startswith("r")]
            pos += list(np.linalg.norm(raw[:, ip], axis=1)) if ip else []
            rot += list(np.linalg.norm(raw[:, ir], axis=1)) if ir else []
        else:
            pos += list(np.abs(raw[:, 0]))
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
    options: Any = None,
    labels: Sequence[str] | None = None,
    progress: Callable[[int, float], None] | None = None,
    weak_bound: tuple[float, float] | None = (0.02, 0.1),
) -> InstrumentIdentification:
    """Identify machine and instrument parameters jointly from several datasets.

    Args:
        mech: nominal mechanism.
        params: the n machine parameters.
        datasets: :class:`Measurements` and/or :class:`InstrumentData` (any mix).
        method: ``"gauss-newton"`` or ``"lm"``.
        options: that solver's options dataclass (``GaussNewtonOptions`` or
            ``LMOptions``; None = its defaults).
        labels: names of the datasets (prefix of the instrument parameter names).
        progress: optional ``(iteration, cost)`` callback passed to the solver.
        weak_bound: (length [m], angle [rad]): a direction of the base set whose 1σ
            (at the files' declared noise) exceeds it is held at nominal too, named in
            the gauge (see :func:`pincal.identification._gauge.weak_parameters`); None
            fits the whole identifiable base set.

    Returns:
        InstrumentIdentification (the machine part is an IdentificationResult).

    Raises:
        SolverOptionError: a method other than the local solvers.
        MeasurementError: inconsistent datasets.
    """
    if method not in ("gauss-newton", "lm"):
        raise SolverOptionError(
            f"joint instrument identification runs 'gauss-newton' or 'lm', not {method!r}"
        )
    entry = solver(method)
    opts = entry.check_options(options)
    model = InstrumentProblem(mech, params, datasets, labels)
    x0 = model.x0
    _, J0, raw0 = model.evaluate(x0)
    ident = model.analyse(x0, J0)
    free = np.sort(model.order[ident.base])
    weak = (np.zeros(0, dtype=int) if weak_bound is None
            else weak_parameters(J0, free, model.units, model.n_machine, weak_bound))  # fmt: skip
    free = np.setdiff1d(free, weak)
    P0, Jp0 = model.tool_points(x0)
    motions = null_motions(J0, Jp0, P0, model.n_machine, ident, model.order,
                           model.names[model.n_machine :])  # fmt: skip
    gauge = tuple(motions.lines())
    if weak.size:
        assert weak_bound is not None
        gauge += (f"seen too weakly to place within {weak_bound[0] * 1e3:g} mm / "
                  f"{weak_bound[1]:g} rad (1σ), held at nominal: "
                  f"{', '.join(model.names[i] for i in weak)}",)  # fmt: skip
    out = entry.solve(model, x0, free, opts, progress)
    r, J, raws = model.evaluate(out.x)
    Jf = J[:, free]
    scale_std = reading_scale_std(Jf, model.whitened_readings(raws))
    if scale_std > SCALE_STD_LIMIT:
        gauge += (f"the length scale: a scale error of the readings (a bar length, a gain) "
                  f"passes into the calibrated machine — the data tell it only to "
                  f"{scale_std * 100:.2g} % (1σ); the scale rests on the instrument's own "
                  "calibration",)  # fmt: skip
    success, message = out.success, out.message
    if not success:
        # at the noise floor a Gauss–Newton step may promise less than the cost changes
        # with the kinematic solver's precision (100× its tolerance per reading)
        step = np.linalg.lstsq(Jf, -r, rcond=None)[0]
        predicted = 0.5 * float(r @ r - np.sum((r + Jf @ step) ** 2))
        sig = np.concatenate([s.ravel() for s in model.sigma])
        jitter = float(np.sum(np.abs(r) * 100 * mech.options.tol / sig))
        if predicted <= max(jitter, 1e-9 * float(r @ r)):
            success = True
            message = (
                f"converged (noise floor: a further step promises {predicted:.3g}, below the "
                f"kinematic precision {jitter:.3g} of the cost; solver: {out.message})"
            )
    dof = max(model.n_equations - free.size, 1)
    chi2 = float(r @ r) / dof
    cov = covariance_from_jacobian(Jf)
    n = model.n_machine
    mach = free < n
    cov_m = cov[np.ix_(mach, mach)]
    mask = np.zeros(n, dtype=bool)
    mask[free[mach]] = True
    x = np.asarray(out.x, dtype=float)
    inst = {k: float(v) for k, v in zip(model.names[n:], x[n:], strict=True)}
    centres_mm = {k: [float(v) * 1e3 for v in c] for k, c in model.socket_centres(x).items()}
    result = IdentificationResult(
        method=method,
        names=params.names,
        units=params.units,
        full_values=x[:n].copy(),
        identified=mask,
        std=np.sqrt(np.clip(np.diag(cov_m), 0.0, None)),
        covariance=cov_m,
        before=_stats(raw0, datasets),
        after=_stats(raws, datasets),
        reduced_chi2=chi2,
        iterations=out.iterations,
        success=success,
        message=f"joint fit of {free.size} of {len(model.names)} parameters (the others "
        "held at nominal: see the gauge); "
        + "".join(f"WARNING: {w}; " for w in model.scale_warnings)
        + message,
        cost_history=tuple(out.history),
        residuals=np.concatenate(  # per pose (a plate's known distances are not poses)
            [np.linalg.norm(a, axis=1) for a in raws[: len(model.datasets)]]
        )[:, None],
        initial_values=np.zeros(n),
        n_equations=model.n_equations,
        model=mech.name,
        preset=params.label,
        extras=out.extras,
        parameter_set=params,
        calibrated_mechanism=model.mechanism(x),
        annotations={
            "instruments": inst,
            "datasets": list(model.labels),
            "redundancy": dof,
            "gauge": list(gauge),
            **({"warnings": list(model.scale_warnings)} if model.scale_warnings else {}),
            **({"socket_centres_mm": centres_mm} if centres_mm else {}),
        },
    )
    ks = {a.shape[1] for a in raws}
    whitened = None
    if len(raws) == len(model.datasets) and len(ks) == 1:
        k = ks.pop()
        whitened = (Jf.reshape(-1, k, free.size), r.reshape(-1, k))
    return InstrumentIdentification(
        result, model.names, x, x0, free, cov, raws, ident, gauge,
        tuple(model.names[i] for i in weak), whitened, model.socket_centres(x),
        model.scale_warnings,
    )  # fmt: skip
