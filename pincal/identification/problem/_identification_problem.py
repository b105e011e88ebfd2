"""The identification problem: mechanism, parameters, one or several data sets, what to fit.

:class:`IdentificationProblem` describes one problem. Every solver of
:func:`pincal.identification.identify` takes one and returns one
:class:`pincal.identification.IdentificationResult`, through one finishing step
(:mod:`pincal.identification.solvers._finish`). Its residual model is

* for one pose file (a :class:`pincal.measure.Measurements`, alone or as the only item of
  a list): :attr:`IdentificationProblem.model`, the batched
  :class:`pincal.identification.CalibrationProblem` (the fast path; every registered
  solver, noise estimated when undeclared, a subset to fit, start values);
* for anything else — several files, or instrument / socket files
  (:class:`pincal.measure.InstrumentData`, :class:`pincal.measure.SocketData`) in any mix
  with pose files: :attr:`IdentificationProblem.joint_model`, the
  :class:`pincal.identification.InstrumentProblem` of machine and instrument unknowns,
  each file whitened by its declared σ (solved by ``"gauss-newton"`` or ``"lm"``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from pincal.errors import MeasurementError, ParameterError
from pincal.identification.problem._instrument_problem import Dataset, InstrumentProblem
from pincal.identification.problem._problem import CalibrationProblem
from pincal.measure import InstrumentData, Measurements, NoiseModel, SocketData
from pincal.model import Mechanism, ParameterSet
from pincal.sensitivity import PLACEMENT_BOUND

__all__ = ["IdentificationProblem"]


@dataclass(frozen=True, eq=False)
class IdentificationProblem:
    """One identification problem, solved by any registered solver.

    Attributes:
        mech: nominal mechanism (the one ``params`` was built for).
        params: the n candidate parameters.
        measurements: one pose file (:class:`pincal.measure.Measurements`: m measured
            poses; their per-value std / noise model weight the residuals, estimated
            from the residuals when neither is given), or a sequence of data sets
            mixing :class:`Measurements`, :class:`pincal.measure.InstrumentData` and
            :class:`pincal.measure.SocketData` (a joint fit of machine and instrument
            unknowns; a sequence holding one pose file is that pose file).
        initial: (n,) start values [m, rad] (None = zeros = nominal); parameters that are
            not fitted stay at these values. One pose file only.
        fit: names of the parameters to fit (None = all); parameters outside stay at
            ``initial``. One pose file only.
        reduce: fit only the identifiable base set of ``fit`` (True), or raise
            :class:`pincal.UnidentifiableError` when it is rank-deficient (False, one
            pose file only: a joint fit always fits its base set).
        noise: declared instrument noise (:class:`pincal.measure.NoiseModel` or
            ``{"position": mm, "orientation": mrad}``), overriding the measurements'
            own; None: the measurements' per-value std or noise model, else the noise is
            estimated from the residuals (variance components per block). One pose file
            only: in a joint fit every file is weighted by its own declared σ.
        labels: a name per data set of a joint fit (prefix of its own unknowns' names;
            default ``"<kind><i>"``); unused for one pose file.
        weak_bound: (length [m], angle [rad]); a direction of the base set whose 1σ
            exceeds it is held at nominal and named (a joint fit's gauge, a pose file's
            message); None fits the whole identifiable base set. A pose file whose noise
            is estimated holds nothing: its σ̂ is not known before the fit, and at an
            unconverged one it would call every direction weak.

    Raises:
        ParameterError: ``initial`` of the wrong shape or non-finite; ``fit`` names a
            parameter outside ``params`` or is empty; ``initial`` / ``fit`` / ``noise``
            / ``reduce=False`` given for a joint fit.
        MeasurementError: no data set, an item that is not a data set, a pose file of a
            joint fit that declares no noise, or data that do not match the mechanism.
    """

    mech: Mechanism
    params: ParameterSet
    measurements: Measurements | Sequence[Dataset]
    initial: np.ndarray | None = None
    fit: Sequence[str] | None = None
    reduce: bool = True
    noise: NoiseModel | Mapping[str, float] | None = None
    labels: Sequence[str] | None = None
    weak_bound: tuple[float, float] | None = PLACEMENT_BOUND

    def __post_init__(self) -> None:
        data = self.measurements
        if not isinstance(data, Measurements):
            if not isinstance(data, (list, tuple)):
                raise MeasurementError(
                    "measurements must be a Measurements or a list of data sets "
                    f"(Measurements, InstrumentData, SocketData), not {type(data).__name__}"
                )
            data = tuple(data)
            kinds = (Measurements, InstrumentData, SocketData)
            odd = [type(d).__name__ for d in data if not isinstance(d, kinds)]
            if odd or not data:
                raise MeasurementError(
                    f"an identification takes Measurements, InstrumentData or SocketData "
                    f"data sets, not {odd}" if odd else "give at least one measurement data set"
                )  # fmt: skip
            if len(data) == 1 and isinstance(data[0], Measurements):
                data = data[0]
            object.__setattr__(self, "measurements", data)
        if self.joint:
            given = [k for k, v in (("initial", self.initial), ("fit", self.fit),
                                    ("noise", self.noise)) if v is not None]  # fmt: skip
            given += [] if self.reduce else ["reduce=False"]
            if given:
                raise ParameterError(
                    f"{', '.join(given)} apply to one pose file; a joint fit of "
                    f"{len(self.datasets)} data sets starts at nominal, fits the identifiable "
                    "base set and weights each file by its declared σ (leave them out)"
                )
        object.__setattr__(self, "noise", NoiseModel.from_spec(self.noise))
        x0 = self.params.check_values(self.initial).copy()
        x0.setflags(write=False)
        object.__setattr__(self, "initial", x0)
        if self.fit is not None:
            names = tuple(str(n) for n in self.fit)
            unknown = [n for n in names if n not in self.params.names]
            if unknown or not names:
                raise ParameterError(
                    f"fit must name parameters of set {self.params.label!r}; unknown: {unknown}"
                    if unknown
                    else "fit is empty; name at least one parameter (or None for all)"
                )
            object.__setattr__(self, "fit", names)
        # check the data against the mechanism up front
        if self.joint:
            self.joint_model  # noqa: B018
        else:
            self.model  # noqa: B018

    @property
    def joint(self) -> bool:
        """True unless the data are one pose file (then the batched model fits it)."""
        return not isinstance(self.measurements, Measurements)

    @property
    def datasets(self) -> tuple[Dataset, ...]:
        """The data sets, in order (one for a pose file)."""
        data = self.measurements
        return (data,) if isinstance(data, Measurements) else tuple(data)

    @property
    def pose_file(self) -> Measurements:
        """The one pose file of a problem that is not joint.

        Raises:
            MeasurementError: the problem has several data sets or instrument files.
        """
        if isinstance(self.measurements, Measurements):
            return self.measurements
        raise MeasurementError(
            f"this problem has {len(self.datasets)} data sets: its residual model is "
            "joint_model, not the batched model of one pose file"
        )

    @cached_property
    def model(self) -> CalibrationProblem:
        """The batched whitened residual model of the one pose file.

        Raises:
            MeasurementError: the problem is joint (use :attr:`joint_model`).
        """
        return CalibrationProblem(self.mech, self.params, self.pose_file, self.noise)

    @cached_property
    def joint_model(self) -> InstrumentProblem:
        """The joint residual model of machine and instrument unknowns over every data set."""
        return InstrumentProblem(self.mech, self.params, self.datasets, self.labels)

    @property
    def x0(self) -> np.ndarray:
        """(n,) start values [SI] (a copy)."""
        return np.array(self.initial, dtype=float)

    @property
    def fit_indices(self) -> np.ndarray:
        """Indices (into ``params``) of the parameters to fit, before reduction."""
        if self.fit is None:
            return np.arange(len(self.params))
        return np.array(sorted(self.params.index(n) for n in self.fit), dtype=int)
