"""The datasets of a joint fit, one class per measurement kind, behind one interface.

:class:`pincal.identification.InstrumentProblem` fits machine parameters and the
instruments' own unknowns to several datasets at once. Each dataset is a
:class:`DataBlock`: k residuals per pose with their σ, its own unknowns (names, units,
start values) and ``residuals(...)`` returning ``measured − model`` with its exact
Jacobian from the tool-point pose and its sensitivities. The kinds:

* :class:`PoseSensorBlock` — a pose sensor (laser tracker, position, component
  subset): its prediction is the measured frame's pose, residuals exactly as in
  :class:`pincal.identification.CalibrationProblem`; no own unknowns.
* :class:`ScalarBlock` — a scalar instrument (:class:`pincal.measure.Instrument`:
  ballbar, probe, planes, gauge, any registered kind): one reading per pose, ``∂v/∂p ·
  ∂p/∂x`` and ``∂v/∂θ``.
* :class:`ArtefactBlock` — an artefact instrument (:class:`pincal.measure.Artefact`:
  the socket plates, any registered kind): k residuals per pose; the unknowns shared
  by the datasets of a kind (a plate's socket centres) live in
  :class:`pincal.identification.problem._shared_terms.SharedUnknowns`.

:func:`data_block` finds the block of a dataset through the kind registry
(:func:`pincal.measure.add_instrument_kind`): a new kind needs no line here.
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

from pincal.errors import MeasurementError
from pincal.identification.problem._problem import CalibrationProblem
from pincal.identification.problem._shared_terms import SharedUnknowns
from pincal.measure import (
    Artefact,
    DeclaredConstant,
    InstrumentData,
    Measurements,
    artefact_class,
    initial_instrument_values,
)
from pincal.model import Mechanism, ParameterSet
from pincal.model.kernels import measurement_residual

__all__ = ["ArtefactBlock", "DataBlock", "PoseSensorBlock", "ScalarBlock", "data_block"]


class DataBlock(ABC):
    """One dataset of a joint fit.

    Attributes:
        data: the dataset; label: its name (prefix of its own unknowns' names).
        sigma: (m, k) 1σ of its residuals [m, rad].
        own_names, own_units: its own unknowns (``"m"`` / ``"rad"``).
        theta0: (len(own_names),) their start values [SI].
    """

    data: Measurements | InstrumentData | Artefact
    label: str
    sigma: np.ndarray
    own_names: tuple[str, ...] = ()
    own_units: tuple[str, ...] = ()
    theta0: np.ndarray = np.zeros(0)

    def __len__(self) -> int:
        return len(self.data)

    @abstractmethod
    def residuals(self, x: np.ndarray, col: int, n: int, P: np.ndarray, Rs: np.ndarray,
                  Jm: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
        """Raw residuals ``measured − model`` (m, k) and their Jacobian (m, k, len(x)).

        Args:
            x: every unknown of the problem (machine first).
            col: the column of this block's own unknowns.
            n: the number of machine parameters.
            P: (m, 3) tool points [m].
            Rs: (m, 3, 3) tool orientations.
            Jm: (m, 6, n) derivative of ``[p_world; rotation (local)]`` of the tool
                w.r.t. the machine parameters (:class:`pincal.sensitivity.BatchSensitivity`
                ``jacobian``); None: no Jacobian (zeros are returned for it).
        """

    def norms(self, raw: np.ndarray) -> tuple[list[float], list[float]]:
        """Per pose position-error and rotation-error norms [m], [rad] of ``raw``."""
        return list(np.linalg.norm(raw, axis=1)), []

    def declared_constants(self, theta: np.ndarray, P: np.ndarray) -> tuple[DeclaredConstant, ...]:
        """The constants its file declares and the fit trusts; none by default.

        See :meth:`pincal.measure.Instrument.declared_constants`.

        Args:
            theta: its own unknowns at the solution.
            P: (m, 3) its tool points [m].
        """
        return ()


class PoseSensorBlock(DataBlock):
    """A pose sensor: the prediction is the measured frame's pose (its measured components)."""

    data: Measurements

    def __init__(self, data: Measurements, label: str, mech: Mechanism, params: ParameterSet,
                 P0: np.ndarray) -> None:  # fmt: skip
        self.data, self.label = data, label
        model = CalibrationProblem(mech, params, data)
        if not model.known_noise:
            raise MeasurementError(
                f"pose data set {label!r} declares no noise; a joint fit weights each file "
                "by its declared σ: give the file a '# noise:' header (or the Measurements a "
                "NoiseModel / per-value std), or fit a pose file alone"
            )
        self.sigma = model.sigma

    def residuals(self, x: np.ndarray, col: int, n: int, P: np.ndarray, Rs: np.ndarray,
                  Jm: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
        d = self.data
        rows = d.component_indices
        m = len(d)
        raw = np.empty((m, rows.size))
        J = np.zeros((m, rows.size, len(x)))
        for i in range(m):
            R_meas = None if d.rotations is None else d.rotations[i]
            r, D = measurement_residual(P[i], Rs[i], d.positions[i], R_meas)
            raw[i] = r[rows]
            if Jm is not None:
                J[i, :, :n] = -(D @ Jm[i])[rows]
        return raw, J

    def norms(self, raw: np.ndarray) -> tuple[list[float], list[float]]:
        comps = self.data.components
        ip = [i for i, c in enumerate(comps) if not c.startswith("r")]
        ir = [i for i, c in enumerate(comps) if c.startswith("r")]
        pos = list(np.linalg.norm(raw[:, ip], axis=1)) if ip else []
        return pos, list(np.linalg.norm(raw[:, ir], axis=1)) if ir else []


class ScalarBlock(DataBlock):
    """Readings of a scalar instrument: one per pose, its own unknowns θ."""

    data: InstrumentData

    def __init__(self, data: InstrumentData, label: str, mech: Mechanism, params: ParameterSet,
                 P0: np.ndarray) -> None:  # fmt: skip
        self.data, self.label = data, label
        self.instrument, self.theta0 = initial_instrument_values(data, P0)
        self.sigma = np.full((len(data), 1), self.instrument.std)
        self.own_names = tuple(f"{label}.{n}" for n in self.instrument.parameter_names)
        self.own_units = tuple(self.instrument.parameter_units)

    def residuals(self, x: np.ndarray, col: int, n: int, P: np.ndarray, Rs: np.ndarray,
                  Jm: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
        k, m = len(self.own_names), len(self.data)
        v, dv_dp, dv_dth = self.instrument.predict(P, x[col : col + k], self.data.ids)
        J = np.zeros((m, 1, len(x)))
        if Jm is not None:
            J[:, 0, :n] = -np.einsum("mi,min->mn", dv_dp, Jm[:, :3])
            J[:, 0, col : col + k] = -dv_dth
        return (self.data.values - v)[:, None], J

    def norms(self, raw: np.ndarray) -> tuple[list[float], list[float]]:
        return list(np.abs(raw[:, 0])), []

    def declared_constants(self, theta: np.ndarray, P: np.ndarray) -> tuple[DeclaredConstant, ...]:
        return self.instrument.declared_constants(P, theta, self.data.ids)


class ArtefactBlock(DataBlock):
    """An artefact dataset: k residuals per pose, own and shared unknowns (see SharedUnknowns)."""

    data: Artefact

    def __init__(self, data: Artefact, label: str, mech: Mechanism, params: ParameterSet,
                 P0: np.ndarray) -> None:  # fmt: skip
        self.data, self.label = data, label
        self.sigma = np.asarray(data.sigma, dtype=float)
        if self.sigma.shape != (len(data), data.dim):
            raise MeasurementError(f"artefact kind {data.kind!r}: sigma must be (m, dim) = "
                                   f"{(len(data), data.dim)}, got {self.sigma.shape}")  # fmt: skip
        self.own_names = tuple(f"{label}.{n}" for n in data.parameter_names)
        self.own_units = tuple(data.parameter_units)
        self.theta0 = np.zeros(len(self.own_names))  # Artefact.start, by SharedUnknowns.start
        self.shared: SharedUnknowns | None = None  # set by the problem once every file is known
        self.index = -1  # the dataset's index in the problem, set with ``shared``

    def residuals(self, x: np.ndarray, col: int, n: int, P: np.ndarray, Rs: np.ndarray,
                  sens: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
        assert self.shared is not None
        return self.shared.block(self.index, x, col, n, P, Rs, sens)


def data_block(d: object, label: str, mech: Mechanism, params: ParameterSet,
               P0: np.ndarray) -> DataBlock:  # fmt: skip
    """The block of dataset ``d`` (``P0``: its nominal tool points (m, 3) [m]).

    Pose measurements are a :class:`PoseSensorBlock`; any other dataset is of a
    registered kind (``d.kind``): a scalar kind's :class:`ScalarBlock`, an artefact
    kind's :class:`ArtefactBlock`.

    Raises:
        MeasurementError: a dataset of no registered kind.
    """
    if isinstance(d, Measurements):
        return PoseSensorBlock(d, label, mech, params, P0)
    if isinstance(d, InstrumentData):
        return ScalarBlock(d, label, mech, params, P0)
    if isinstance(d, Artefact):
        cls = artefact_class(d.kind)
        if cls is not type(d):
            raise MeasurementError(
                f"{type(d).__name__} has the kind name {d.kind!r} of {cls.__name__}; give it "
                "its own kind name and register it with add_instrument_kind"
            )
        return ArtefactBlock(d, label, mech, params, P0)
    raise MeasurementError(
        "a joint fit takes pose measurements, scalar instrument readings (InstrumentData) "
        f"or datasets of a registered artefact kind, not {type(d).__name__}"
    )
