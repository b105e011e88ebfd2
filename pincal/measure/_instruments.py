"""Readings of a scalar instrument at m poses, their start values and their simulation.

The instrument kinds themselves (ballbar, sphere probe, planes, dial gauge, and any
registered one) are :class:`pincal.measure.Instrument` subclasses
(:mod:`pincal.measure._instrument_kinds`); the machine part of the identification
Jacobian is ``∂v/∂p · ∂p/∂x`` with ``∂p/∂x`` from
:func:`pincal.sensitivity.pose_sensitivity`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from pincal.errors import MeasurementError
from pincal.measure._instrument_kind import Instrument
from pincal.model import Mechanism

__all__ = ["InstrumentData", "initial_instrument_values", "simulate_instrument"]


@dataclass(frozen=True, eq=False)
class InstrumentData:
    """Scalar readings of one instrument at m poses.

    Attributes:
        instrument: the instrument (kind, noise, geometry).
        q_act: (m, n_act) commanded actuator values [m, rad].
        values: (m,) readings [m].
        actuated: actuated joint names (columns of ``q_act``).
        frame: the measured frame whose origin is the tool point.
        ids: (m,) integer ids of the kind's ``id_column`` (e.g. the plane of each
            contact), else None.
        initial: (k,) start values of θ, or None (estimated from the nominal model).

    Raises:
        MeasurementError: inconsistent shapes, non-finite values, bad ids.
    """

    instrument: Instrument
    q_act: np.ndarray
    values: np.ndarray
    actuated: tuple[str, ...]
    frame: str
    ids: np.ndarray | None = None
    initial: np.ndarray | None = field(default=None)

    def __post_init__(self) -> None:
        if not isinstance(self.instrument, Instrument):
            raise MeasurementError(f"instrument must be an Instrument, got {self.instrument!r}")
        q = np.atleast_2d(np.asarray(self.q_act, dtype=float))
        v = np.asarray(self.values, dtype=float).reshape(-1)
        if q.shape != (v.size, len(self.actuated)):
            raise MeasurementError(
                f"q_act must be ({v.size}, {len(self.actuated)}) for {v.size} readings, "
                f"got {q.shape}"
            )
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
            raise MeasurementError("instrument data contain NaN or inf")
        object.__setattr__(self, "q_act", q)
        object.__setattr__(self, "values", v)
        object.__setattr__(self, "actuated", tuple(self.actuated))
        object.__setattr__(self, "ids", self.instrument.check_ids(self.ids, v.size))
        if self.initial is not None:
            x0 = np.asarray(self.initial, dtype=float).reshape(-1)
            object.__setattr__(self, "initial", x0)

    def __len__(self) -> int:
        return self.values.size

    @property
    def kind(self) -> str:
        """The kind of instrument that took these readings (see ``instrument_kinds()``)."""
        return self.instrument.kind


def initial_instrument_values(
    data: InstrumentData, positions: np.ndarray
) -> tuple[Instrument, np.ndarray]:
    """The instrument with its reference geometry and start values θ0 from tool positions.

    Fits the instrument to the tool positions of the nominal model
    (:meth:`Instrument.start`), unless ``data.initial`` gives θ0 (the reference
    geometry is then still filled in).

    Args:
        data: the readings.
        positions: (m, 3) nominal tool positions [m].

    Returns:
        (instrument with its reference geometry, θ0 (k,)).

    Raises:
        MeasurementError: ``data.initial`` of the wrong length.
    """
    P = np.asarray(positions, dtype=float)
    inst, theta = data.instrument.start(P, data.values, data.ids)
    if data.initial is None:
        return inst, theta
    k = len(inst.parameter_names)
    if data.initial.size != k:
        raise MeasurementError(f"initial has {data.initial.size} values, {inst.kind} needs {k}")
    return inst, data.initial.copy()


def simulate_instrument(
    actual: Mechanism,
    instrument: Instrument,
    theta: np.ndarray,
    q_act_rows: np.ndarray,
    rng: np.random.Generator | None = None,
    ids: np.ndarray | None = None,
    noise: bool = True,
) -> InstrumentData:
    """Readings of ``instrument`` (true parameters θ) on the ``actual`` machine.

    Args:
        actual: the machine measured (simulation truth).
        instrument: the instrument.
        theta: (k,) its true parameter values [m, rad] (see
            :attr:`Instrument.parameter_names`).
        q_act_rows: (m, n_act) actuator values [m, rad].
        rng: generator for the noise (default: a fresh one).
        ids: (m,) ids of the kind's id column (e.g. plane ids).
        noise: add N(0, std²) to each reading.

    Returns:
        InstrumentData (``initial`` None).

    Raises:
        MeasurementError: bad θ or ids; ConvergenceError: a row cannot be assembled.
    """
    rows = np.atleast_2d(np.asarray(q_act_rows, dtype=float))
    P = np.array([actual.frame_placement(q).translation for q in actual.configurations(rows)])
    v = instrument.predict(P, theta, ids)[0]
    if noise:
        rng = rng if rng is not None else np.random.default_rng()
        v = v + rng.normal(0.0, instrument.std, v.shape)
    return InstrumentData(instrument, rows.copy(), v, actual.actuated, actual.measured_frame, ids)
